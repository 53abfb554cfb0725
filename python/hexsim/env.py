"""Gymnasium environments: a hexapod on the paper's rough terrain.

``hexsim/HexapodRough-v0``: the action is the 18 joints' targets, as offsets from the gait's
standing pose scaled to [-1, 1]; ``hexsim/HexapodGait-v0``: the action is the gait's velocity
command (forward, sideways, turn), scaled to [-1, 1], and the gait fitted to the robot walks.

Both observe the body's attitude (roll, pitch), its velocity and angular velocity (world frame),
the height of its hips above the ground, the joints' angles and velocities and which feet touch
the ground. The reward is the forward progress (m, along the starting heading, x) minus
``energy_weight`` times the servos' mechanical work (J, Σ|τ·ω|·dt) over the action's time; an
episode ends (terminated) when the body tilts past ``fall_tilt_deg`` or the simulation diverges,
and is truncated at the scenario's duration. The terrain's seed is drawn from ``reset``'s seed,
so each episode walks a new ground and the same seed gives the same one.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ._hexsim import DivergedError, Simulation, step_many

FEET = 6


class HexapodEnv(gym.Env):
    """A hexapod walking on rough ground, one action every ``control_dt`` seconds.

    ``scenario`` and ``fields`` are ``hexsim.Simulation``'s (default: hex18's tripod on the
    paper's natural terrain, 10 s); ``action`` is ``"joints"`` or ``"gait"``.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scenario: str | None = None,
        action: str = "joints",
        control_dt: float = 0.02,
        action_scale: float = 0.5,
        max_command: tuple[float, float, float] = (0.2, 0.1, 30.0),
        energy_weight: float = 0.001,
        fall_tilt_deg: float = 45.0,
        record: str | None = None,
        **fields: Any,
    ):
        if action not in ("joints", "gait"):
            raise ValueError(f"action: {action!r}, expected 'joints' or 'gait'")
        self.sim = Simulation(scenario, record=record, **fields)
        if control_dt < self.sim.dt:
            raise ValueError(f"control_dt: {control_dt} s is shorter than the step {self.sim.dt} s")
        self.mode = action
        self.frame_skip = max(1, round(control_dt / self.sim.dt))
        self.action_scale = float(action_scale)
        self.max_command = np.asarray(max_command, dtype=np.float64)
        self.energy_weight = float(energy_weight)
        self.fall_tilt = math.radians(fall_tilt_deg)
        n = len(self.sim.joint_names)
        self.limits = np.asarray(self.sim.joint_limits, dtype=np.float64)
        size = n if action == "joints" else 3
        self.action_space = spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)
        # roll, pitch, velocity (3), angular velocity (3), hips' height, joints (2n), feet (6)
        self.observation_space = spaces.Box(
            -np.inf, np.inf, shape=(2 + 3 + 3 + 1 + 2 * n + FEET,), dtype=np.float64
        )
        self.standing = np.zeros(n)
        self._x = 0.0
        self._energy = 0.0

    def _observe(self, state: dict) -> np.ndarray:
        return np.concatenate(
            [
                state["body_rpy"][:2],
                state["body_velocity"],
                state["body_angular_velocity"],
                [state["body_height"]],
                state["joint_angles"],
                state["joint_velocities"],
                state["foot_contact"].astype(np.float64),
            ]
        )

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.sim.step(self._begin_reset())
        return self._end_reset()

    def step(self, action):
        self._act(action)
        try:
            self.sim.step(self.frame_skip)
        except DivergedError:
            pass  # the outcome reads it from the simulation
        return self._outcome()

    # The parts of reset and step around the physics, so that HexapodVectorEnv steps the worlds'
    # physics together (hexsim.step_many) and does the rest exactly as here.

    def _begin_reset(self) -> int:
        """Draws the terrain and restarts; returns the steps to stand through the settle time."""
        self._terrain_seed = int(self.np_random.integers(0, 2**31 - 1))
        self.sim.reset(seed=self._terrain_seed)
        return max(1, round(self.sim.settle_time / self.sim.dt))

    def _end_reset(self):
        # the gait's standing pose at the end of the settle time is the action's centre
        state = self.sim.state()
        self.standing = state["joint_targets"].copy()
        self._x = float(state["body_position"][0])
        self._energy = self.sim.servo_energy
        return self._observe(state), {"terrain_seed": self._terrain_seed}

    def _act(self, action) -> None:
        action = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        if self.mode == "joints":
            targets = np.clip(
                self.standing + self.action_scale * action, self.limits[:, 0], self.limits[:, 1]
            )
            self.sim.set_joint_targets(targets)
        else:
            self.sim.set_command(*(action * self.max_command))

    def _outcome(self):
        diverged = self.sim.failure
        energy = self.sim.servo_energy
        work, self._energy = energy - self._energy, energy
        state = self.sim.state()
        x = float(state["body_position"][0])
        reward = (x - self._x) - self.energy_weight * work
        self._x = x
        roll, pitch = state["body_rpy"][:2]
        fallen = max(abs(roll), abs(pitch)) > self.fall_tilt
        terminated = bool(fallen or diverged)
        truncated = bool(not terminated and self.sim.remaining == 0)
        info = {"work": work, "x": x}
        if diverged:
            info["diverged"] = diverged
        return self._observe(state), float(reward), terminated, truncated, info

    def close(self):
        self.sim.close()


class HexapodVectorEnv(VectorEnv):
    """``num_envs`` hexapod worlds stepped together: Gymnasium's ``VectorEnv``, next-step
    autoreset (Gymnasium 1.x's default), each world's physics on a thread of its own
    (``hexsim.step_many``, the GIL released), up to ``threads`` (default: the machine's cores).

    World ``i`` is ``HexapodEnv(**kwargs)`` reset with ``seed + i``, exactly as in
    ``gymnasium.vector.SyncVectorEnv``: the same observations, rewards and ends, bit for bit,
    whatever the threads.
    """

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 2, threads: int | None = None, **kwargs: Any):
        if num_envs < 1:
            raise ValueError(f"num_envs: {num_envs}, expected at least 1")
        if threads is not None and threads < 1:
            raise ValueError(f"threads: {threads}, expected at least 1")
        self.envs = [HexapodEnv(**kwargs) for _ in range(num_envs)]
        self.num_envs = num_envs
        self.threads = threads
        self.single_observation_space = self.envs[0].observation_space
        self.single_action_space = self.envs[0].action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._autoreset = np.zeros(num_envs, dtype=np.bool_)

    def _step_physics(self, worlds: list[int], steps: list[int]) -> None:
        step_many([self.envs[i].sim for i in worlds], steps, threads=self.threads)

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: {len(seeds)} seeds for {self.num_envs} worlds")
        settle = []
        for env, s in zip(self.envs, seeds):
            gym.Env.reset(env, seed=s)
            settle.append(env._begin_reset())
        self._step_physics(list(range(self.num_envs)), settle)
        observations, infos = [], {}
        for i, env in enumerate(self.envs):
            obs, info = env._end_reset()
            observations.append(obs)
            infos = self._add_info(infos, info, i)
        self._autoreset[:] = False
        return np.stack(observations), infos

    def step(self, actions):
        actions = np.asarray(actions)
        resetting = [i for i in range(self.num_envs) if self._autoreset[i]]
        stepping = [i for i in range(self.num_envs) if not self._autoreset[i]]
        counts = {}
        for i in resetting:
            counts[i] = self.envs[i]._begin_reset()
        for i in stepping:
            self.envs[i]._act(actions[i])
            counts[i] = self.envs[i].frame_skip
        order = resetting + stepping
        self._step_physics(order, [counts[i] for i in order])
        observations = [None] * self.num_envs
        rewards = np.zeros(self.num_envs, dtype=np.float64)
        terminations = np.zeros(self.num_envs, dtype=np.bool_)
        truncations = np.zeros(self.num_envs, dtype=np.bool_)
        infos = {}
        for i, env in enumerate(self.envs):
            if self._autoreset[i]:
                observations[i], info = env._end_reset()
            else:
                observations[i], rewards[i], terminations[i], truncations[i], info = env._outcome()
            infos = self._add_info(infos, info, i)
        self._autoreset = np.logical_or(terminations, truncations)
        return np.stack(observations), rewards, terminations, truncations, infos

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()


def register() -> None:
    """Registers the environments with Gymnasium (done on ``import hexsim``); ``gym.make_vec(id,
    num_envs=N, vectorization_mode="vector_entry_point")`` makes a ``HexapodVectorEnv``."""
    for env_id, action in (("hexsim/HexapodRough-v0", "joints"), ("hexsim/HexapodGait-v0", "gait")):
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point=HexapodEnv,
                vector_entry_point=HexapodVectorEnv,
                kwargs={"action": action},
            )
