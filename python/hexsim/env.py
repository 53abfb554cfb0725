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

The work on a world — the action applied, the physics stepped, the observation, reward and ends
read — is Rust's (``hexsim._hexsim.Task``), one code for the single environment and for the
vector environment, which does it for all its worlds in one call on a thread pool
(``step_tasks``, the GIL released). Python keeps the seeding (the environments' ``np_random``)
and Gymnasium's bookkeeping: autoreset, infos.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ._hexsim import DivergedError, Simulation, Task, step_tasks


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
        self.limits = np.asarray(self.sim.joint_limits, dtype=np.float64)
        self.task = Task(
            self.sim,
            action,
            self.frame_skip,
            action_scale=self.action_scale,
            max_command=tuple(self.max_command),
            energy_weight=self.energy_weight,
            fall_tilt=self.fall_tilt,
        )
        self.action_space = spaces.Box(-1.0, 1.0, shape=(self.task.action_size,), dtype=np.float32)
        # roll, pitch, velocity (3), angular velocity (3), hips' height, joints (2n), feet (6)
        self.observation_space = spaces.Box(
            -np.inf, np.inf, shape=(self.task.observation_size,), dtype=np.float64
        )
        self._terrain_seed = None

    @property
    def standing(self) -> np.ndarray:
        """The gait's standing pose at the end of the episode's settle time: the joint action's
        centre."""
        return self.task.standing

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._terrain_seed = self._draw_terrain_seed()
        obs = self.task.reset(self.sim, self._terrain_seed)
        if self.sim.failure:
            raise DivergedError(self.sim.failure)
        return obs, {"terrain_seed": self._terrain_seed}

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        obs, reward, terminated, truncated, work, x, diverged = self.task.step(self.sim, action)
        info = {"work": work, "x": x}
        if diverged:
            info["diverged"] = diverged
        return obs, reward, terminated, truncated, info

    def _draw_terrain_seed(self) -> int:
        """The next episode's terrain seed, from the environment's ``np_random`` (the vector
        environment draws its worlds' here too, so that they equal single environments')."""
        return int(self.np_random.integers(0, 2**31 - 1))

    def close(self):
        self.sim.close()


class HexapodVectorEnv(VectorEnv):
    """``num_envs`` hexapod worlds stepped together: Gymnasium's ``VectorEnv``, next-step
    autoreset (Gymnasium 1.x's default), each world on a thread of its own (``step_tasks``: the
    action, the physics, the observation, reward and ends, in one call, the GIL released), up to
    ``threads`` (default: the machine's cores).

    World ``i`` is ``HexapodEnv(**kwargs)`` reset with ``seed + i``, exactly as in
    ``gymnasium.vector.SyncVectorEnv``: the same observations, rewards, ends and infos, bit for
    bit, whatever the threads.
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
        self._sims = [env.sim for env in self.envs]
        self._tasks = [env.task for env in self.envs]
        self._autoreset = np.zeros(num_envs, dtype=np.bool_)
        self._no_seeds = [None] * num_envs

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed: {len(seeds)} seeds for {self.num_envs} worlds")
        for env, s in zip(self.envs, seeds):
            gym.Env.reset(env, seed=s)
        everyone = np.ones(self.num_envs, dtype=np.bool_)
        terrain = self._draw_terrain_seeds(everyone)
        no_actions = np.zeros(self.action_space.shape, dtype=np.float64)
        obs, *_ = step_tasks(self._sims, self._tasks, no_actions, terrain, threads=self.threads)
        self._autoreset[:] = False
        return obs, self._infos(everyone, terrain, None, None, None)

    def step(self, actions):
        actions = np.asarray(actions, dtype=np.float64)
        resetting = self._autoreset
        if resetting.any():
            self._check(actions)
            terrain = self._draw_terrain_seeds(resetting)
        else:
            # the common step, kept short: its Python runs serially between the worlds' steps
            terrain = self._no_seeds
        obs, rewards, terminations, truncations, work, x, diverged = step_tasks(
            self._sims, self._tasks, actions, terrain, threads=self.threads
        )
        self._autoreset = terminations | truncations
        infos = self._infos(resetting, terrain, work, x, diverged)
        return obs, rewards, terminations, truncations, infos

    def _check(self, actions: np.ndarray) -> None:
        """Refuses the actions before any terrain seed is drawn (``step_tasks`` checks them too,
        with the same messages, but after the resetting worlds' seeds are drawn)."""
        if actions.shape != self.action_space.shape:
            raise ValueError(f"action: shape {actions.shape}, expected {self.action_space.shape}")
        if np.isnan(actions).any():
            world, component = np.argwhere(np.isnan(actions))[0]
            raise ValueError(
                f"action: NaN in world {world}'s action, component {component}; "
                "expected numbers in [-1, 1]"
            )

    def _draw_terrain_seeds(self, resetting: np.ndarray) -> list[int | None]:
        """The terrain seeds of the worlds that reset (None for the others), each drawn from its
        environment's ``np_random`` as a single environment's reset draws it."""
        return [env._draw_terrain_seed() if r else None for env, r in zip(self.envs, resetting)]

    def _infos(self, resetting, terrain, work, x, diverged) -> dict[str, Any]:
        """The infos as ``VectorEnv._add_info`` batches the single environments' (a value array
        and a ``_key`` mask per key, a key only if some world has it): ``terrain_seed`` for the
        worlds reset, ``work`` and ``x`` (and ``diverged``) for the worlds stepped."""
        if terrain is self._no_seeds and not any(diverged):
            # the common step, every world stepped, none diverged: no mask arithmetic
            everyone = np.ones(self.num_envs, dtype=np.bool_)
            return {"work": work, "_work": everyone, "x": x, "_x": everyone.copy()}
        infos: dict[str, Any] = {}
        if resetting.any():
            infos["terrain_seed"] = np.array([s or 0 for s in terrain], dtype=int)
            infos["_terrain_seed"] = resetting.copy()
        stepped = ~resetting
        if work is not None and stepped.any():
            infos["work"], infos["_work"] = work, stepped
            infos["x"], infos["_x"] = x, stepped.copy()
            if any(diverged):
                infos["diverged"] = np.array(diverged, dtype=object)
                infos["_diverged"] = np.array([d is not None for d in diverged])
        return infos

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
