"""A random policy in the Gymnasium environment hexsim/HexapodRough-v0: joint targets around the
standing pose, one every 20 ms, on a new natural terrain every episode.

    python examples/random_policy.py [--episodes 3] [--duration 5]
"""

import argparse

import gymnasium as gym

import hexsim  # noqa: F401  (registers the environments)

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--episodes", type=int, default=3)
parser.add_argument("--duration", type=float, default=5.0, help="seconds per episode at most")
args = parser.parse_args()

env = gym.make("hexsim/HexapodRough-v0", duration=args.duration, action_scale=0.2)
for episode in range(args.episodes):
    obs, info = env.reset(seed=episode)
    total, steps, done = 0.0, 0, False
    while not done:
        obs, reward, terminated, truncated, step_info = env.step(env.action_space.sample())
        total += reward
        steps += 1
        done = terminated or truncated
    end = "fell" if terminated else "time up"
    print(f"episode {episode}: terrain seed {info['terrain_seed']}, {steps} actions, "
          f"return {total:+.4f} ({end})")
env.close()
