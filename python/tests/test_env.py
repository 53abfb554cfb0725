"""The Gymnasium environments: Gymnasium's own checker, seeding, rewards, episode ends."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import hexsim  # noqa: F401  (registers the environments)

IDS = ["hexsim/HexapodRough-v0", "hexsim/HexapodGait-v0"]


@pytest.mark.parametrize("env_id", IDS)
def test_passes_gymnasiums_checker(env_id):
    env = gym.make(env_id, duration=2.0)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_the_same_seed_gives_the_same_episode(env_id):
    def episode(seed):
        env = gym.make(env_id, duration=1.0)
        obs, info = env.reset(seed=seed)
        env.action_space.seed(seed)
        observations, rewards = [obs], []
        for _ in range(10):
            obs, reward, *_ = env.step(env.action_space.sample())
            observations.append(obs)
            rewards.append(reward)
        env.close()
        return np.array(observations), rewards, info["terrain_seed"]

    a, b, c = episode(1), episode(1), episode(2)
    np.testing.assert_array_equal(a[0], b[0])
    assert a[1] == b[1] and a[2] == b[2]
    assert a[2] != c[2], "the reset seed draws the terrain's"


def test_the_gait_environment_walks_forward_for_a_forward_command():
    env = gym.make("hexsim/HexapodGait-v0", duration=3.0)
    env.reset(seed=0)
    total, steps, truncated = 0.0, 0, False
    while not truncated:
        _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0, 0.0], dtype=np.float32))
        assert not terminated
        total += reward
        steps += 1
    # 3 s at 0.2 m/s commanded, less the energy term: forward progress is the reward's bulk
    assert steps == 150, "truncated at the scenario's duration (3 s / 0.02 s)"
    assert 0.3 < total < 0.7, total
    env.close()


def test_standing_still_earns_nothing_and_a_fall_terminates(root):
    flat = str(root / "terrains" / "flat.toml")
    env = gym.make("hexsim/HexapodRough-v0", duration=2.0, fall_tilt_deg=5.0, terrain=flat)
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    _, reward, terminated, _, info = env.step(zero)
    assert abs(reward) < 1e-3 and not terminated  # the standing pose holds, level
    # throw the left legs' joints to one side: the body tilts past 5°
    action = np.zeros_like(zero)
    action[:9] = 1.0
    for _ in range(50):
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    assert terminated
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_the_vector_environment_equals_the_single_ones_bit_for_bit(env_id, root):
    # 0.6 s episodes: truncated after 30 actions, so the autoreset is compared too
    kwargs = dict(duration=0.6, terrain=str(root / "terrains" / "natural.toml"))
    action = "joints" if env_id.endswith("Rough-v0") else "gait"
    vector = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point", **kwargs)
    assert isinstance(vector, hexsim.HexapodVectorEnv) and vector.num_envs == 3
    singles = gym.vector.SyncVectorEnv(
        [lambda: hexsim.HexapodEnv(action=action, **kwargs) for _ in range(3)]
    )
    a, b = vector.reset(seed=11), singles.reset(seed=11)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1]["terrain_seed"], b[1]["terrain_seed"])
    rng = np.random.default_rng(0)
    truncated = 0
    for k in range(40):
        actions = rng.uniform(-1, 1, size=vector.action_space.shape).astype(np.float32)
        got, want = vector.step(actions), singles.step(actions)
        for x, y in zip(got[:4], want[:4]):
            np.testing.assert_array_equal(x, y, err_msg=f"action {k}")
        truncated += int(got[3].sum())
    assert truncated == 3, "each world truncated once, then reset"
    vector.close()
    singles.close()
