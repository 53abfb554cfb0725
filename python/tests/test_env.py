"""The Gymnasium environments: Gymnasium's own checker, seeding, rewards, episode ends."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import hexsim  # noqa: F401  (registers the environments)
from hexsim._hexsim import Task, step_tasks

IDS = ["hexsim/HexapodRough-v0", "hexsim/HexapodGait-v0"]


def _assert_infos_equal(got, want, err_msg):
    assert set(got) == set(want), err_msg
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=f"{err_msg}, info {key}")
        assert got[key].dtype == want[key].dtype, f"{err_msg}, info {key}"


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


@pytest.mark.parametrize("threads", [None, 1])
@pytest.mark.parametrize("env_id", IDS)
def test_the_vector_environment_equals_the_single_ones_bit_for_bit(env_id, threads, root):
    # 0.6 s episodes: truncated after 30 actions, so the autoreset is compared too
    kwargs = dict(duration=0.6, terrain=str(root / "terrains" / "natural.toml"))
    action = "joints" if env_id.endswith("Rough-v0") else "gait"
    vector = gym.make_vec(
        env_id, num_envs=3, vectorization_mode="vector_entry_point", threads=threads, **kwargs
    )
    assert isinstance(vector, hexsim.HexapodVectorEnv) and vector.num_envs == 3
    singles = gym.vector.SyncVectorEnv(
        [lambda: hexsim.HexapodEnv(action=action, **kwargs) for _ in range(3)]
    )
    a, b = vector.reset(seed=11), singles.reset(seed=11)
    np.testing.assert_array_equal(a[0], b[0])
    _assert_infos_equal(a[1], b[1], "reset")
    rng = np.random.default_rng(0)
    ended = np.zeros(3, dtype=bool)
    for k in range(40):
        actions = rng.uniform(-1, 1, size=vector.action_space.shape).astype(np.float32)
        got, want = vector.step(actions), singles.step(actions)
        for x, y in zip(got[:4], want[:4]):
            np.testing.assert_array_equal(x, y, err_msg=f"action {k}")
        _assert_infos_equal(got[4], want[4], f"action {k}")
        # truncated at 30 actions, or terminated before by a fall the random joints caused
        ended |= got[2] | got[3]
    assert ended.all(), "each world's episode ended, then reset"
    vector.close()
    singles.close()


@pytest.mark.parametrize("env_id", IDS)
def test_bad_actions_raise_clear_errors_and_change_nothing(env_id, root):
    kwargs = dict(duration=0.1, terrain=str(root / "terrains" / "natural.toml"))
    action = "joints" if env_id.endswith("Rough-v0") else "gait"
    single = gym.make(env_id, **kwargs)
    single.reset(seed=0)
    size = single.action_space.shape[0]
    with pytest.raises(ValueError, match=rf"shape \({size + 1},\), expected \({size},\)"):
        single.step(np.zeros(size + 1))
    with pytest.raises(ValueError, match="NaN in component 1"):
        single.step(np.array([0.0, np.nan] + [0.0] * (size - 2)))
    single.close()
    vector = hexsim.HexapodVectorEnv(2, action=action, **kwargs)
    singles = gym.vector.SyncVectorEnv(
        [lambda: hexsim.HexapodEnv(action=action, **kwargs) for _ in range(2)]
    )
    vector.reset(seed=3), singles.reset(seed=3)
    zero = np.zeros((2, size), dtype=np.float32)
    nan = zero.copy()
    nan[1, 2] = np.nan
    for k in range(12):  # 5 actions an episode: autoresets pending at some of the bad calls
        with pytest.raises(ValueError, match=r"shape \(2, 1\)"):
            vector.step(np.zeros((2, 1)))
        with pytest.raises(ValueError, match="NaN in world 1's action, component 2"):
            vector.step(nan)
        with pytest.raises(ValueError, match="could not convert"):
            vector.step([["a"] * size] * 2)
        actions = np.full((2, size), 0.1 * (k % 3), dtype=np.float32)
        got, want = vector.step(actions), singles.step(actions)
        for x, y in zip(got[:4], want[:4]):
            np.testing.assert_array_equal(x, y, err_msg=f"action {k}")
        _assert_infos_equal(got[4], want[4], f"action {k}")
    vector.close()
    singles.close()


def test_the_low_level_calls_refuse_bad_input():
    def task(sim, action="gait"):
        return Task(sim, action, 20, action_scale=0.5, max_command=(0.2, 0.1, 30.0),
                    energy_weight=0.0, fall_tilt=1.0)

    sims = [hexsim.Simulation(duration=1.0) for _ in range(2)]
    tasks = [task(sim) for sim in sims]
    actions = np.zeros((2, 3))
    with pytest.raises(hexsim.HexsimError, match="2 simulations, 1 tasks, 2 seeds"):
        step_tasks(sims, tasks[:1], actions, [None, None])
    with pytest.raises(hexsim.HexsimError, match="same action"):
        step_tasks(sims, [tasks[0], task(sims[1], "joints")], actions, [None, None])
    with pytest.raises(hexsim.HexsimError, match="threads"):
        step_tasks(sims, tasks, actions, [None, None], threads=0)
    with pytest.raises(RuntimeError, match="borrowed"):  # one world twice
        step_tasks([sims[0], sims[0]], tasks, actions, [None, None])
    with pytest.raises(ValueError, match=r"shape \(3,\), expected \(2, 3\)"):
        step_tasks(sims, tasks, actions[0], [None, None])
    with pytest.raises(ValueError, match="NaN in world 1's action, component 0"):
        step_tasks(sims, tasks, np.array([[0.0] * 3, [np.nan] * 3]), [None, None])
    with pytest.raises(ValueError, match="'walk', expected 'joints' or 'gait'"):
        task(sims[0], "walk")
    sims[1].close()
    with pytest.raises(hexsim.HexsimError, match="simulation 1 is closed"):
        step_tasks(sims, tasks, actions, [None, None])
    # a reset starts a closed world again
    obs, reward, terminated, truncated, work, x, diverged = step_tasks(sims, tasks, actions, [1, 2])
    assert obs.shape == (2, tasks[0].observation_size) and not reward.any() and not work.any()
    assert diverged == [None, None]
    step_tasks(sims, tasks, actions, [None, None])


def test_a_diverging_world_ends_its_episode_and_says_why():
    # a step past the contact spring's stability limit, forced: the worlds leave physics
    kwargs = dict(action="gait", duration=2.0, dt=0.01, allow_unstable_dt=True, settle=0.01)
    vector = hexsim.HexapodVectorEnv(2, **kwargs)
    singles = gym.vector.SyncVectorEnv([lambda: hexsim.HexapodEnv(**kwargs) for _ in range(2)])
    vector.reset(seed=0), singles.reset(seed=0)
    for k in range(6):  # diverged, then reset, then on
        got, want = vector.step(np.zeros((2, 3))), singles.step(np.zeros((2, 3)))
        for x, y in zip(got[:4], want[:4]):
            np.testing.assert_array_equal(x, y, err_msg=f"action {k}")
        _assert_infos_equal(got[4], want[4], f"action {k}")
        if "diverged" in got[4]:
            assert got[2][got[4]["_diverged"]].all(), "terminated"
            assert all("diverged at" in why for why in got[4]["diverged"][got[4]["_diverged"]])
            break
    assert "diverged" in got[4]
    vector.close()
    singles.close()
