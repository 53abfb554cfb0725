"""hexsim.Simulation against the command line, for determinism, and on bad input."""

import json
import math
import subprocess

import numpy as np
import pytest

import hexsim


def run_to_end(sim):
    sim.step(sim.remaining)
    sim.close()
    return sim.metrics()


def test_arguments_give_hexsim_runs_metrics_bit_for_bit(hexsim_bin, tmp_path):
    metrics = tmp_path / "run.json"
    subprocess.run(
        [hexsim_bin, "run", "--duration", "2", "--seed", "7", "--no-record", "--metrics", str(metrics)],
        check=True,
        capture_output=True,
    )
    python = run_to_end(hexsim.Simulation(duration=2.0, seed=7))
    written = json.loads(metrics.read_text())
    # the file ends with where the run came from; the metrics before it are the same
    assert written.pop("metadata")["seed"] == 7
    assert python == written
    assert python["complete"] and python["forward_distance"] > 0.1


def test_a_scenario_file_gives_the_batchs_metrics_bit_for_bit(hexsim_bin, root, tmp_path):
    scenario = root / "scenarios" / "natural_tripod.toml"
    results = tmp_path / "results.jsonl"
    subprocess.run(
        [hexsim_bin, "batch", str(scenario), "-q", "-j", "1", "-o", str(results),
         "--record-dir", str(tmp_path)],
        check=True,
        capture_output=True,
    )
    batch = json.loads(results.read_text().splitlines()[0])["metrics"]
    # stepped in uneven stretches: the same run, whatever the stretches
    sim = hexsim.Simulation(str(scenario))
    for n in (1, 7, 500, 3):
        assert sim.step(n) == n
    assert run_to_end(sim) == batch


def test_the_same_seed_gives_the_same_state_bit_for_bit():
    def states(seed):
        sim = hexsim.Simulation(duration=1.0)
        sim.reset(seed=seed)
        sim.step(1500)
        return sim.state()

    a, b, c = states(3), states(3), states(4)
    for key, value in a.items():
        np.testing.assert_array_equal(value, b[key], err_msg=key)
    assert not np.array_equal(a["body_position"], c["body_position"]), "the seed changes the ground"


def test_reset_starts_again_and_its_seed_is_the_terrains():
    sim = hexsim.Simulation(duration=1.0)
    assert sim.seed == 5489  # natural.toml's own
    sim.step(300)
    first = sim.state()
    sim.reset(seed=11)
    assert sim.seed == 11 and sim.steps == 0
    sim.reset()
    assert sim.seed == 5489
    sim.step(300)
    np.testing.assert_array_equal(sim.state()["joint_angles"], first["joint_angles"])


def test_a_step_hexsim_chose_is_a_note_not_a_warning(root):
    kraby = root / "tests/data/third_party/kraby/hexapod.urdf"
    sim = hexsim.Simulation(robot=str(kraby), duration=0.01)
    assert sim.dt == 0.00025
    assert any(n.startswith("dt: 0.250 ms, not the default 1 ms") for n in sim.notes), sim.notes
    assert not any(w.startswith("dt:") for w in sim.warnings), sim.warnings


def test_state_shapes_and_units():
    sim = hexsim.Simulation(duration=1.0)
    sim.step(sim.remaining)
    s = sim.state()
    n = len(sim.joint_names)
    assert n == 18 and sim.leg_names == ["lf", "lm", "lr", "rf", "rm", "rr"]
    for key in ("joint_angles", "joint_velocities", "joint_targets", "joint_torques"):
        assert s[key].shape == (n,)
    assert s["foot_positions"].shape == (6, 3) and s["foot_forces"].shape == (6, 3)
    assert s["foot_contact"].dtype == bool
    assert sim.joint_limits.shape == (n, 2)
    assert math.isclose(float(np.linalg.norm(s["body_quaternion"])), 1.0, rel_tol=1e-9)
    assert s["time"] == pytest.approx(2.0)
    assert (s["foot_penetration"][s["foot_contact"]] > 0).all()
    assert (s["foot_penetration"][~s["foot_contact"]] == 0).all()


def test_standing_the_feet_carry_the_weight():
    """Static load sharing: standing still, the ground's vertical forces sum to m·g."""
    sim = hexsim.Simulation(duration=1.0)
    sim.step(800)  # of the 1 s settle
    vertical = []
    for _ in range(200):
        sim.step()
        s = sim.state()
        assert s["settling"]
        vertical.append(s["foot_forces"][:, 2].sum())
    assert np.mean(vertical) == pytest.approx(sim.mass * 9.81, rel=1e-3)


def test_a_velocity_command_steers_the_gait():
    sim = hexsim.Simulation(duration=4.0)
    sim.step(1000)  # settle
    sim.set_command(0.0, 0.0, 30.0)
    sim.step(sim.remaining)
    m = sim.metrics()
    assert m["heading_change_deg"] > 45, m["heading_change_deg"]
    assert abs(m["forward_distance"]) < 0.1


def test_joint_targets_drive_the_servos():
    sim = hexsim.Simulation(duration=3.0)
    sim.step(1000)
    standing = sim.state()["joint_targets"].copy()
    targets = standing.copy()
    targets[0] += 0.3  # the first joint swings 0.3 rad; the robot stands on
    sim.step(1000, targets=targets)
    s = sim.state()
    np.testing.assert_array_equal(s["joint_targets"], targets)
    assert s["joint_angles"][0] == pytest.approx(targets[0], abs=0.05)
    assert sim.metrics()["forward_distance"] == pytest.approx(0.0, abs=0.05)
    sim.set_joint_targets(None)  # back to the gait: it walks
    sim.step(sim.remaining)
    assert sim.metrics()["forward_distance"] > 0.05


def test_the_end_of_the_scenario_and_close(tmp_path):
    record = tmp_path / "walk.rrd"
    sim = hexsim.Simulation(duration=0.5, record=str(record))
    assert sim.step(10**9) == sim.steps == 1500
    assert sim.step(10) == 0 and sim.remaining == 0
    written = sim.close()
    assert str(record) in [str(p) for p in written] and record.stat().st_size > 0
    assert sim.metrics()["complete"]
    with pytest.raises(hexsim.HexsimError, match="closed"):
        sim.step()


def test_a_dotted_field_changes_one_field_of_a_table(tmp_path):
    # as a sweep names it: the rest of the file's table stays, where a whole table replaces it
    scenario = tmp_path / "walk.toml"
    scenario.write_text("duration = 1.0\n[start]\nx = -1.0\ny = 0.2\n")
    dotted = hexsim.Simulation(str(scenario), **{"start.y": 0.1})
    whole = hexsim.Simulation(str(scenario), start={"y": 0.1})
    for sim in (dotted, whole):
        sim.step()
    x, y, _ = dotted.state()["body_position"]
    assert abs(x - -1.0) < 0.01 and abs(y - 0.1) < 0.01, (x, y)
    x, y, _ = whole.state()["body_position"]  # x: the default, 0.75 m inside the edge
    assert abs(x - -1.25) < 0.01 and abs(y - 0.1) < 0.01, (x, y)
    with pytest.raises(hexsim.HexsimError, match="stiffnes"):
        hexsim.Simulation(str(scenario), **{"contact.stiffnes": 3e4})
    with pytest.raises(hexsim.HexsimError, match="`start.x` is a float"):
        hexsim.Simulation(str(scenario), **{"start.x.y": 1.2})


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"scenario": "no/such/scenario.toml"}, "no/such/scenario.toml: cannot read"),
        ({"robot": "no_such_robot.urdf", "duration": 1.0}, "no_such_robot.urdf"),
        ({"duration": -1.0}, "duration"),
        ({"contact": {"stiffnes": 1e4}}, "stiffnes"),
        ({"dt": float("nan")}, "dt"),
    ],
)
def test_bad_input_raises_the_clis_message(kwargs, message):
    with pytest.raises(hexsim.HexsimError, match=message.replace(".", r"\.")):
        hexsim.Simulation(**kwargs)


def test_bad_calls_raise_not_crash(root):
    with pytest.raises(hexsim.HexsimError, match="sweep"):
        hexsim.Simulation(str(root / "scenarios" / "sweep_contact.toml"))
    with pytest.raises(hexsim.HexsimError, match="ball"):
        hexsim.Simulation(str(root / "scenarios" / "ball_natural.toml"))
    sim = hexsim.Simulation(duration=1.0)
    with pytest.raises(hexsim.HexsimError, match="18 joints"):
        sim.set_joint_targets([0.0] * 5)
    with pytest.raises(hexsim.HexsimError, match="finite"):
        sim.set_joint_targets([float("nan")] * 18)
    with pytest.raises(hexsim.HexsimError, match="finite"):
        sim.set_command(float("inf"))
    with pytest.raises(hexsim.HexsimError, match="sequence"):
        sim.set_joint_targets("eighteen")
    with pytest.raises(hexsim.HexsimError, match="take a step"):
        sim.state()
    with pytest.raises(OverflowError):
        sim.step(-1)


def test_a_diverging_simulation_raises_and_keeps_its_files(tmp_path):
    metrics = tmp_path / "m.json"
    # a step past the contact spring's stability limit, forced: the feet sink through the ground
    sim = hexsim.Simulation(duration=2.0, metrics=str(metrics), dt=0.01, allow_unstable_dt=True)
    with pytest.raises(hexsim.DivergedError, match="stability limit"):
        sim.step(sim.remaining)
    assert "sank" in sim.failure
    with pytest.raises(hexsim.DivergedError):
        sim.step()
    sim.close()
    assert not json.loads(metrics.read_text())["complete"]


def test_step_many_steps_each_world_as_step_would_on_any_threads():
    def worlds(seeds, step, **kwargs):
        sims = [hexsim.Simulation(duration=1.0, seed=s) for s in seeds]
        for n in (1, 130, 7):
            step(sims, n, **kwargs)
        return [s.state() for s in sims] + [s.metrics() for s in sims]

    def one_by_one(sims, n):
        for sim in sims:
            sim.step(n)

    seeds = [3, 4, 5]
    alone = worlds(seeds, one_by_one)
    for threads in (1, 2, 3):
        together = worlds(seeds, hexsim.step_many, threads=threads)
        for a, b in zip(alone[:3], together[:3]):
            for key in a:
                np.testing.assert_array_equal(a[key], b[key], err_msg=f"{key}, {threads} threads")
        assert alone[3:] == together[3:]


def test_step_many_counts_per_world_and_divergence_without_raising():
    calm = hexsim.Simulation(duration=1.0)
    wild = hexsim.Simulation(duration=2.0, dt=0.01, allow_unstable_dt=True)
    taken = hexsim.step_many([calm, wild], [10, wild.remaining])
    assert taken[0] == 10 and 0 < taken[1] < 200
    assert calm.failure is None and "sank" in wild.failure
    assert hexsim.step_many([calm, wild], 5) == [5, 0], "a diverged world takes no step"
    with pytest.raises(hexsim.HexsimError, match="3 counts for 2 simulations"):
        hexsim.step_many([calm, wild], [1, 2, 3])
    with pytest.raises(hexsim.HexsimError, match="threads"):
        hexsim.step_many([calm], 1, threads=0)
    wild.close()
    with pytest.raises(hexsim.HexsimError, match="simulation 1 is closed"):
        hexsim.step_many([calm, wild], 1)
