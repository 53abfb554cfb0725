"""Steps per second stepping hexsim from Python: n steps per call, one step per call, and the
Gymnasium environment, on hex18's tripod on the natural terrain (the workload of `hexsim bench`'s
multibody walk). Compare the first with `hexsim bench`'s "walk, multibody" figure.

    python examples/bench.py [--steps 20000] [--repeats 3]
"""

import argparse
import time

import gymnasium as gym

import hexsim

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--steps", type=int, default=20000)
parser.add_argument("--repeats", type=int, default=3)
args = parser.parse_args()


def best(measure):
    return max(measure() for _ in range(args.repeats))


def n_per_call():
    sim = hexsim.Simulation(duration=args.steps * 1e-3)
    start = time.perf_counter()
    taken = sim.step(sim.remaining)
    return taken / (time.perf_counter() - start)


def one_per_call():
    sim = hexsim.Simulation(duration=args.steps * 1e-3)
    step = sim.step
    start = time.perf_counter()
    for _ in range(sim.remaining):
        step()
    return args.steps / (time.perf_counter() - start)


def one_per_call_with_state():
    sim = hexsim.Simulation(duration=args.steps * 1e-3)
    start = time.perf_counter()
    for _ in range(sim.remaining):
        sim.step()
        sim.state()
    return args.steps / (time.perf_counter() - start)


def environment():
    env = gym.make("hexsim/HexapodGait-v0", duration=args.steps * 1e-3)
    env.reset(seed=0)
    action = env.action_space.sample() * 0
    start = time.perf_counter()
    actions = 0
    while True:
        *_, terminated, truncated, _ = env.step(action)
        actions += 1
        if terminated or truncated:
            break
    return actions * env.unwrapped.frame_skip / (time.perf_counter() - start)


for label, measure in [
    ("n steps per call", n_per_call),
    ("1 step per call", one_per_call),
    ("1 step per call + state()", one_per_call_with_state),
    ("HexapodGait-v0, 20 steps per action", environment),
]:
    print(f"{label:38s} {best(measure):9.0f} steps/s")
