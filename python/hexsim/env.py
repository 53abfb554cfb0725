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

from ._hexsim import DivergedError, Simulation

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
        terrain_seed = int(self.np_random.integers(0, 2**31 - 1))
        self.sim.reset(seed=terrain_seed)
        # stand through the scenario's settle time: the gait's standing pose is the action's centre
        self.sim.step(max(1, round(self.sim.settle_time / self.sim.dt)))
        state = self.sim.state()
        self.standing = state["joint_targets"].copy()
        self._x = float(state["body_position"][0])
        self._energy = self.sim.metrics()["servo_energy"]
        return self._observe(state), {"terrain_seed": terrain_seed}

    def step(self, action):
        action = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        if self.mode == "joints":
            targets = np.clip(
                self.standing + self.action_scale * action, self.limits[:, 0], self.limits[:, 1]
            )
            self.sim.set_joint_targets(targets)
        else:
            self.sim.set_command(*(action * self.max_command))
        diverged = None
        try:
            self.sim.step(self.frame_skip)
        except DivergedError as e:
            diverged = str(e)
        energy = self.sim.metrics()["servo_energy"]
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


def register() -> None:
    """Registers the environments with Gymnasium (done on ``import hexsim``)."""
    for env_id, action in (("hexsim/HexapodRough-v0", "joints"), ("hexsim/HexapodGait-v0", "gait")):
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=HexapodEnv, kwargs={"action": action})
