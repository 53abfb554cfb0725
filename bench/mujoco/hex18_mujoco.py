"""hex18 in MuJoCo, an equivalent of `hexsim bench`'s walk, to compare speeds on one machine.

The model is built from hexsim's own files: robots/hex18.urdf (masses, inertias, joint axes,
ranges, the 10 mm foot spheres), the natural terrain exported by `hexsim terrain export --csv`
as a height field, position servos with hex18's gains (20 N·m/rad, 0.05 N·m·s/rad) limited to its
3 N·m effort, dt = 1 ms, a free base, contacts only between the feet and the ground (MuJoCo's
soft contact, its defaults; not the paper's spring-damper). The tripod is open loop in joint
space (hexsim's is a foot-space gait with inverse kinematics; the controller's cost is small
beside a step either way): period 1 s, duty 0.5, hex18's standing pose (femur −20°, tibia 98°)
with the coxa sweeping ±0.2 rad and the femur lifting 0.35 rad in swing.

Usage: python3 hex18_mujoco.py TERRAIN.csv [--steps 21000] [--repeats 3] [--urdf hex18.urdf]
                                          [--json OUT.json]
Prints steps/s for a Python loop (the controller each step) and for mujoco.rollout (the same
controls precomputed), best of the repeats, and where the base ended (it must walk, not fall);
`--json` also writes them (what `hexsim bench --mujoco` reads).
"""
import argparse
import json
import math
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def rpy_quat(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (math.cos(r / 2), math.sin(r / 2), math.cos(p / 2),
                              math.sin(p / 2), math.cos(y / 2), math.sin(y / 2))
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


def mjcf(urdf: Path, heights: np.ndarray, size: float) -> str:
    robot = ET.parse(urdf).getroot()
    links = {l.get("name"): l for l in robot.findall("link")}
    children = {}
    for j in robot.findall("joint"):
        children.setdefault(j.find("parent").get("link"), []).append(j)

    def vec(e, attr, default="0 0 0"):
        return [float(v) for v in (e.get(attr) if e is not None and e.get(attr) else default).split()]

    def body(name, indent):
        link = links[name]
        out = []
        inertial = link.find("inertial")
        i = inertial.find("inertia")
        out.append(f'{indent}<inertial pos="{" ".join(map(str, vec(inertial.find("origin"), "xyz")))}" '
                   f'mass="{inertial.find("mass").get("value")}" '
                   f'diaginertia="{i.get("ixx")} {i.get("iyy")} {i.get("izz")}"/>')
        for c in link.findall("collision"):
            s = c.find("geometry/sphere")
            if s is not None:
                out.append(f'{indent}<geom type="sphere" size="{s.get("radius")}" '
                           f'pos="{" ".join(map(str, vec(c.find("origin"), "xyz")))}" contype="1" conaffinity="0" '
                           f'condim="3" friction="0.8 0.005 0.0001"/>')
        for j in children.get(name, []):
            child = j.find("child").get("link")
            o = j.find("origin")
            q = rpy_quat(vec(o, "rpy"))
            lim = j.find("limit")
            out.append(f'{indent}<body name="{child}" pos="{" ".join(map(str, vec(o, "xyz")))}" '
                       f'quat="{" ".join(map(str, q))}">')
            out.append(f'{indent}  <joint name="{j.get("name")}" type="hinge" axis="{j.find("axis").get("xyz")}" '
                       f'range="{lim.get("lower")} {lim.get("upper")}" limited="true"/>')
            out.extend(body(child, indent + "  "))
            out.append(f"{indent}</body>")
        return out

    joints = [j.get("name") for j in robot.iter("joint")]
    actuators = "\n".join(
        f'    <position joint="{n}" kp="20" kv="0.05" forcerange="-3 3" forcelimited="true" ctrlrange="-3 3"/>'
        for n in joints)
    rows, cols = heights.shape
    top = float(heights.max() - heights.min()) or 1e-3
    return f"""<mujoco model="hex18">
  <option timestep="0.001" integrator="implicitfast"/>
  <asset><hfield name="ground" nrow="{rows}" ncol="{cols}" size="{size / 2} {size / 2} {top} 0.1"/></asset>
  <worldbody>
    <geom type="hfield" hfield="ground" contype="0" conaffinity="1"/>
    <body name="base_link" pos="-1.25 0 0.2">
      <freejoint/>
{chr(10).join(body("base_link", "      "))}
    </body>
  </worldbody>
  <actuator>
{actuators}
  </actuator>
</mujoco>"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("terrain_csv")
    ap.add_argument("--size", type=float, default=4.0, help="terrain side (m)")
    ap.add_argument("--steps", type=int, default=21000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--urdf", type=Path, default=ROOT / "robots/hex18.urdf")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    ap.add_argument("--warmup", action="store_true",
                    help="run each measurement once untimed first (a process's first run is "
                         "slower: with one timed run, the rollout read 26,000 steps/s against "
                         "35,000 for the best of five)")
    args = ap.parse_args()
    heights = np.loadtxt(args.terrain_csv, delimiter=",", comments="#")
    model = mujoco.MjModel.from_xml_string(mjcf(args.urdf, heights, args.size))
    low = heights.min()
    model.hfield_data[:] = ((heights - low) / (heights.max() - low)).ravel()
    # the base starts above the ground's height there
    data = mujoco.MjData(model)
    legs = ["lf", "lm", "lr", "rf", "rm", "rr"]
    tripod = {"lf": 0.0, "rm": 0.0, "lr": 0.0, "rf": 0.5, "lm": 0.5, "rr": 0.5}
    names = [model.actuator(i).name or model.joint(model.actuator_trnid[i][0]).name
             for i in range(model.nu)]
    joint_of = [model.joint(model.actuator_trnid[i][0]).name for i in range(model.nu)]

    def controls(t):
        u = np.zeros(model.nu)
        for k, joint in enumerate(joint_of):
            leg, part = joint.split("_")[0], joint.split("_")[1]
            phase = (t / 1.0 + tripod[leg]) % 1.0
            swing = phase >= 0.5
            s = (phase - 0.5) / 0.5 if swing else phase / 0.5
            side = 1.0 if leg[0] == "l" else -1.0
            if part == "coxa":
                # stance sweeps back, swing forward
                u[k] = -side * (0.2 * (1 - 2 * s) if not swing else -0.2 * (1 - 2 * s))
            elif part == "femur":
                u[k] = math.radians(-20) - (0.35 * math.sin(math.pi * s) if swing else 0.0)
            else:
                u[k] = math.radians(98)
        return u

    ctrl = np.array([controls(k * 0.001) for k in range(args.steps)])
    data.qpos[2] = 0.2 + heights.max()
    mujoco.mj_forward(model, data)
    start = (data.qpos.copy(), data.qvel.copy())

    def reset():
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = start
        mujoco.mj_forward(model, data)

    figures = {"mujoco_version": mujoco.__version__, "steps": args.steps, "repeats": args.repeats}
    best = 0.0
    for repeat in range(args.repeats + args.warmup):
        reset()
        t0 = time.perf_counter()
        for k in range(args.steps):
            data.ctrl[:] = ctrl[k]
            mujoco.mj_step(model, data)
        if repeat >= args.warmup:
            best = max(best, args.steps / (time.perf_counter() - t0))
    x, y, z = data.qpos[:3]
    w, qx, qy, qz = data.qpos[3:7]
    tilt = math.degrees(math.acos(max(-1, min(1, 1 - 2 * (qx * qx + qy * qy)))))
    print(f"mujoco {mujoco.__version__}: python loop {best:.0f} steps/s (best of {args.repeats}); "
          f"base from (-1.25, 0) to ({x:.3f}, {y:.3f}, {z:.3f}) m, tilt {tilt:.1f}°, "
          f"{data.ncon} contacts at the end")
    figures["loop_steps_per_second"] = best
    figures["base_end"] = [float(x), float(y), float(z)]
    figures["tilt_deg"] = tilt
    figures["rollout_steps_per_second"] = None
    try:
        from mujoco import rollout
        best = 0.0
        for repeat in range(args.repeats + args.warmup):
            reset()
            state = np.empty(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
            mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
            t0 = time.perf_counter()
            rollout.rollout(model, data, state, ctrl[None, :, :])
            if repeat >= args.warmup:
                best = max(best, args.steps / (time.perf_counter() - t0))
        print(f"mujoco rollout (controls precomputed): {best:.0f} steps/s (best of {args.repeats})")
        figures["rollout_steps_per_second"] = best
    except Exception as e:  # rollout's API differs across versions
        print(f"mujoco rollout not measured: {e}")
    if args.json:
        args.json.write_text(json.dumps(figures))


if __name__ == "__main__":
    main()
