"""hex18 walks the paper's natural terrain from Python: forward, then a turn, then it stops;
its state read every half second, its metrics at the end, the walk recorded for the viewer.

    python examples/walk_hex18.py [--duration 12] [--record walk.rrd]
"""

import argparse

import numpy as np

import hexsim

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--duration", type=float, default=12.0, help="seconds walked")
parser.add_argument("--record", default=None, help="a .rrd file for the rerun viewer")
args = parser.parse_args()

sim = hexsim.Simulation(duration=args.duration, seed=7, record=args.record)
sim.step(round(sim.settle_time / sim.dt))  # stand
third = round(args.duration / 3 / sim.dt)
for command in [(0.1, 0.0, 0.0), (0.05, 0.0, 20.0), (0.0, 0.0, 0.0)]:
    sim.set_command(*command)
    for _ in range(6):
        sim.step(third // 6)
        s = sim.state()
        roll, pitch, yaw = np.degrees(s["body_rpy"])
        x, y, _ = s["body_position"]
        feet = "".join("●" if c else "○" for c in s["foot_contact"])
        print(f"t {s['time']:5.2f} s  x {x:+.3f} y {y:+.3f} m  yaw {yaw:+6.1f}°  "
              f"tilt {max(abs(roll), abs(pitch)):4.1f}°  feet {feet}")
sim.step(sim.remaining)
written = sim.close()
m = sim.metrics()
print(f"walked {m['distance']:.3f} m, turned {m['heading_change_deg']:.1f}°, "
      f"cost of transport {m['cost_of_transport']:.2f}; wrote {', '.join(map(str, written)) or 'nothing'}")
