"""Steps per second stepping hexsim from Python: n steps per call, one step per call, and the
Gymnasium environment, on hex18's tripod on the natural terrain (the workload of `hexsim bench`'s
multibody walk); then many worlds at once: `step_many` and Python threads each stepping a
`Simulation`, and the vector environment, each against one world stepped the same way (one
`Simulation`; one `HexapodGait-v0`); and the vector environment's serial work per world and
action (CPU time, which a busy machine hardly changes). Compare the first with `hexsim bench`'s
"walk, multibody" figure.

Each scaling figure is the median of `--repeats` ratios, each from one world and N worlds
measured back to back (in alternating order), so that a machine whose speed drifts between
measurements (shared vCPUs) moves both sides of a ratio alike.

    python examples/bench.py [--steps 20000] [--repeats 3] [--worlds N (default: the cores)]
"""

import argparse
import os
import statistics
import threading
import time

import gymnasium as gym
import numpy as np

import hexsim

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--steps", type=int, default=20000)
parser.add_argument("--repeats", type=int, default=3)
parser.add_argument("--worlds", type=int, default=os.cpu_count() or 1)
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


def worlds_step_many(worlds):
    sims = [hexsim.Simulation(duration=args.steps * 1e-3) for _ in range(worlds)]
    start = time.perf_counter()
    taken = sum(hexsim.step_many(sims, sims[0].remaining))
    return taken / (time.perf_counter() - start)


def worlds_threads(worlds):
    def walk(out, k):
        sim = hexsim.Simulation(duration=args.steps * 1e-3)  # a Simulation stays in its thread
        barrier.wait()
        out[k] = sim.step(sim.remaining)

    barrier = threading.Barrier(worlds + 1)
    taken = [0] * worlds
    threads = [threading.Thread(target=walk, args=(taken, k)) for k in range(worlds)]
    for t in threads:
        t.start()
    barrier.wait()
    start = time.perf_counter()
    for t in threads:
        t.join()
    return sum(taken) / (time.perf_counter() - start)


def vector_environment(worlds):
    env = hexsim.HexapodVectorEnv(worlds, action="gait", duration=args.steps * 1e-3)
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    start = time.perf_counter()
    actions = 0
    while True:
        *_, terminated, truncated, _ = env.step(action)
        actions += 1
        if (terminated | truncated).any():
            break
    return actions * worlds * env.envs[0].frame_skip / (time.perf_counter() - start)


def vector_serial_work():
    """µs of the calling thread's CPU time per world and action that a HexapodVectorEnv spends
    around the physics (an upper bound of its serial part: on one thread, the worlds'
    observations and rewards count too). CPU time, not wall time, so a busy machine hardly
    changes it: one step per action, less the same steps taken bare."""
    actions = 1000
    sims = [hexsim.Simulation(duration=10.0) for _ in range(args.worlds)]
    start = time.thread_time()
    for _ in range(actions):
        hexsim.step_many(sims, 1, threads=1)
    bare = time.thread_time() - start
    env = hexsim.HexapodVectorEnv(
        args.worlds, threads=1, action="joints", control_dt=1e-3, duration=10.0
    )
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    start = time.thread_time()
    for _ in range(actions):
        env.step(action)
    return (time.thread_time() - start - bare) / (actions * args.worlds) * 1e6


single = [
    ("n steps per call", n_per_call),
    ("1 step per call", one_per_call),
    ("1 step per call + state()", one_per_call_with_state),
    ("HexapodGait-v0, 20 steps per action", environment),
]
for label, measure in single:
    print(f"{label:38s} {best(measure):9.0f} steps/s")


def scaling(one, many):
    """The median over the repeats of many worlds' steps/s over one world's, the two measured
    back to back, in alternating order; and the medians of the two rates."""
    ones, manys, ratios = [], [], []
    for r in range(args.repeats):
        if r % 2:
            b, a = many(), one()
        else:
            a, b = one(), many()
        ones.append(a)
        manys.append(b)
        ratios.append(b / a)
    return statistics.median(ratios), statistics.median(ones), statistics.median(manys), ratios


w = args.worlds
for label, one, many in [
    (f"{w} worlds, step_many", lambda: worlds_step_many(1), lambda: worlds_step_many(w)),
    (f"{w} worlds, a Python thread each", lambda: worlds_threads(1), lambda: worlds_threads(w)),
    (f"HexapodVectorEnv, {w} worlds", environment, lambda: vector_environment(w)),
    (f"  against a HexapodVectorEnv of 1", lambda: vector_environment(1), lambda: vector_environment(w)),
]:
    ratio, a, b, ratios = scaling(one, many)
    spread = f"{min(ratios):.2f}–{max(ratios):.2f}"
    print(f"{label:38s} {b:9.0f} steps/s  ({ratio:.2f}× one world at {a:.0f}; {spread})")
serial = min(vector_serial_work() for _ in range(args.repeats))
print(f"{'HexapodVectorEnv, serial work':38s} {serial:9.1f} µs CPU per world and action")
