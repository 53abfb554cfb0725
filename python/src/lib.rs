//! hexsim from Python: a walk scenario stepped a stretch at a time, its state as NumPy arrays.
//!
//! Thin by design: every number comes from the library's [`WalkSession`], the run `hexsim run`
//! makes, so a scenario stepped to its end here gives `hexsim run --metrics`'s metrics bit for
//! bit. Errors are the library's messages, raised as `hexsim.HexsimError`.
//!
//! Many worlds at once: [`step_many`] steps several simulations on the worlds' thread pool
//! ([`pool`]), the GIL released; the Gymnasium environments' work on a world — action,
//! physics, observation, reward, episode ends — is [`env`]'s, for one world or for many in one
//! call.

use hexsim::gait::VelocityCommand;
use hexsim::runner::Outputs;
use hexsim::runner::walk::WalkSession;
use hexsim::scenario::{self, Scenario};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};

mod env;
mod pool;

create_exception!(
    _hexsim,
    HexsimError,
    PyException,
    "An error from hexsim: bad input (a scenario, robot, terrain or gait that does not load), a \
     file that cannot be written, or a call that does not fit the simulation's state."
);
create_exception!(
    _hexsim,
    DivergedError,
    HexsimError,
    "The simulation left physics (the watchdog's message says what, where and the likely cause)."
);

fn error(e: impl std::fmt::Display) -> PyErr {
    HexsimError::new_err(format!("{e:#}"))
}

/// Where a scenario given as arguments resolves relative paths, and how its errors name it.
fn arguments_origin() -> PathBuf {
    std::env::current_dir()
        .unwrap_or_default()
        .join("hexsim.Simulation(arguments)")
}

/// The scenario: a file, a file with some fields replaced, or fields alone (the scenario file's
/// field names; relative paths against the current folder).
fn load(file: Option<&Path>, fields: Option<toml::Table>) -> Result<Scenario, String> {
    match (file, fields) {
        (Some(file), None) => {
            let mut scenarios = scenario::load_file(file).map_err(|e| e.to_string())?;
            if scenarios.len() != 1 {
                return Err(format!(
                    "{}: a sweep of {} scenarios; give one scenario (`hexsim batch` runs sweeps)",
                    file.display(),
                    scenarios.len()
                ));
            }
            Ok(scenarios.remove(0))
        }
        (Some(file), Some(fields)) => {
            let text = std::fs::read_to_string(file)
                .map_err(|e| format!("{}: cannot read the scenario file: {e}", file.display()))?;
            let mut table: toml::Table = text
                .parse()
                .map_err(|e: toml::de::Error| format!("{}: {e}", file.display()))?;
            if table.contains_key("sweep") {
                return Err(format!(
                    "{}: a sweep; give one scenario (`hexsim batch` runs sweeps)",
                    file.display()
                ));
            }
            lay_over(&mut table, fields)?;
            let name = file
                .file_stem()
                .map_or("scenario".into(), |s| s.to_string_lossy().into_owned());
            scenario::from_table(table, name, file).map_err(|e| e.to_string())
        }
        (None, fields) => {
            let mut table = toml::Table::new();
            lay_over(&mut table, fields.unwrap_or_default())?;
            // `hexsim run`'s walk when no duration is given
            table
                .entry("duration")
                .or_insert(toml::Value::Float(scenario::spec::RUN_DURATION));
            scenario::from_table(table, "python".into(), &arguments_origin())
                .map_err(|e| e.to_string())
        }
    }
}

/// Lays the keyword arguments over a scenario's table as sweeps and comparisons do
/// (`scenario::overlay`): a name is a field, whole (`contact={...}` replaces the table), or a
/// dotted path to one (`**{"contact.stiffness": 3e4}` changes that field alone).
fn lay_over(table: &mut toml::Table, fields: toml::Table) -> Result<(), String> {
    for (path, value) in fields {
        scenario::overlay::set(table, &path, value).map_err(|e| format!("`{path}`: {e}"))?;
    }
    Ok(())
}

/// Python keyword arguments as a scenario's TOML fields: dicts, lists, numbers, strings and
/// booleans; None leaves a field out. An error names the field, as a scenario file's would.
fn fields_of(kwargs: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (key, value) in kwargs.iter() {
        let key: String = key.extract()?;
        if let Some(value) = toml_of(&value, &key)? {
            table.insert(key, value);
        }
    }
    Ok(table)
}

fn toml_of(value: &Bound<'_, PyAny>, field: &str) -> PyResult<Option<toml::Value>> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyString};
    let fail = |expected: &str| {
        error(format!(
            "scenario field `{field}`: {}: expected {expected}",
            value.repr().map_or("?".into(), |r| r.to_string())
        ))
    };
    Ok(Some(if value.is_none() {
        return Ok(None);
    } else if value.is_instance_of::<PyBool>() {
        toml::Value::Boolean(value.extract()?)
    } else if value.is_instance_of::<PyInt>() {
        toml::Value::Integer(value.extract().map_err(|_| fail("a 64-bit integer"))?)
    } else if value.is_instance_of::<PyFloat>() {
        let x: f64 = value.extract()?;
        if !x.is_finite() {
            return Err(fail("a finite number"));
        }
        toml::Value::Float(x)
    } else if value.is_instance_of::<PyString>() {
        toml::Value::String(value.extract()?)
    } else if let Ok(dict) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (key, item) in dict.iter() {
            let key: String = key.extract().map_err(|_| fail("text keys"))?;
            if let Some(item) = toml_of(&item, &format!("{field}.{key}"))? {
                table.insert(key, item);
            }
        }
        toml::Value::Table(table)
    } else if let Ok(items) = value.try_iter() {
        let mut array = Vec::new();
        for (i, item) in items.enumerate() {
            if let Some(item) = toml_of(&item?, &format!("{field}[{i}]"))? {
                array.push(item);
            }
        }
        toml::Value::Array(array)
    } else if let Ok(x) = value.extract::<f64>() {
        // NumPy scalars and other numbers
        if !x.is_finite() {
            return Err(fail("a finite number"));
        }
        toml::Value::Float(x)
    } else {
        return Err(fail("a number, text, boolean, list or dict"));
    }))
}

/// A hexapod walk scenario, stepped from Python.
///
/// `Simulation(scenario=None, *, record=None, trajectory=None, metrics=None, **fields)`:
/// `scenario` is a scenario file; `fields` are a scenario file's fields (`robot`, `terrain`,
/// `gait`, `contact`, `servo`, `duration`, `dt`, `seed`, `start`, …), replacing the file's, or
/// dotted paths to one field of a table (`**{"contact.stiffness": 3e4}`, as a sweep names it);
/// `record`, `trajectory`, `metrics` are the files `hexsim run --record/--trajectory/--metrics`
/// would write, rewritten at every `reset`.
#[pyclass(unsendable, module = "hexsim._hexsim")]
struct Simulation {
    /// As loaded.
    scenario: Scenario,
    /// Resolved again with the seed of the last `reset(seed=…)`.
    reseeded: Option<Scenario>,
    record: Option<PathBuf>,
    trajectory: Option<PathBuf>,
    metrics_file: Option<PathBuf>,
    session: Option<WalkSession>,
    /// The last finished run's metrics (JSON), after `close`.
    final_metrics: Option<serde_json::Value>,
}

impl Simulation {
    fn current(&self) -> &Scenario {
        self.reseeded.as_ref().unwrap_or(&self.scenario)
    }

    fn session(&self) -> PyResult<&WalkSession> {
        self.session
            .as_ref()
            .ok_or_else(|| error("the simulation is closed: call reset() to start it again"))
    }

    fn session_mut(&mut self) -> PyResult<&mut WalkSession> {
        self.session
            .as_mut()
            .ok_or_else(|| error("the simulation is closed: call reset() to start it again"))
    }

    fn start(&mut self) -> PyResult<()> {
        let outputs = Outputs::files(
            self.record.clone(),
            self.trajectory.clone(),
            self.metrics_file.clone(),
        );
        self.session = Some(self.current().start_walk(outputs).map_err(error)?);
        self.final_metrics = None;
        Ok(())
    }

    /// After steps: a session stopped by an output's error is finished, which raises it (as
    /// `step` does, naming the files still written); one stopped by a divergence stays, for its
    /// state to be read.
    fn finish_if_stopped(&mut self) -> PyResult<()> {
        let stopped = self
            .session
            .as_ref()
            .is_some_and(|s| s.stopped() && s.failure().is_none());
        if stopped {
            self.finish()?;
        }
        Ok(())
    }

    fn finish(&mut self) -> PyResult<Vec<PathBuf>> {
        let Some(session) = self.session.take() else {
            return Ok(Vec::new());
        };
        let outcome = session.finish().map_err(error)?;
        self.final_metrics = Some(serde_json::to_value(&outcome.metrics).map_err(error)?);
        Ok(outcome.written)
    }
}

fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(error)?;
    py.import("json")?.call_method1("loads", (text,))
}

#[pymethods]
impl Simulation {
    #[new]
    #[pyo3(signature = (scenario=None, *, record=None, trajectory=None, metrics=None, **fields))]
    fn new(
        scenario: Option<PathBuf>,
        record: Option<PathBuf>,
        trajectory: Option<PathBuf>,
        metrics: Option<PathBuf>,
        fields: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let fields = match fields {
            Some(f) if !f.is_empty() => Some(fields_of(f)?),
            _ => None,
        };
        let loaded = load(scenario.as_deref(), fields).map_err(error)?;
        let mut sim = Simulation {
            scenario: loaded,
            reseeded: None,
            record,
            trajectory,
            metrics_file: metrics,
            session: None,
            final_metrics: None,
        };
        sim.start()?;
        Ok(sim)
    }

    /// Starts the scenario again from its start; `seed` replaces the terrain generator's seed
    /// (as `seed = …` in the file). The files asked for are finished and written anew.
    #[pyo3(signature = (seed=None))]
    fn reset(&mut self, seed: Option<u32>) -> PyResult<()> {
        self.finish()?;
        self.reseeded = match seed {
            Some(seed) => Some(self.scenario.with_seed(seed).map_err(error)?),
            None => None,
        };
        self.start()
    }

    /// Takes up to `n` steps of `dt` and returns how many were taken: fewer at the end of the
    /// scenario's settle time and duration (see `remaining`) or on Ctrl-C. `command` (forward
    /// m/s, sideways m/s, turn °/s) steers the gait from now on, replacing the scenario's
    /// schedule; `targets` (rad, one per joint in `joint_names` order) drive the servos from now
    /// on instead of the gait. Raises DivergedError if the simulation leaves physics.
    #[pyo3(signature = (n=1, *, command=None, targets=None))]
    fn step(
        &mut self,
        py: Python<'_>,
        n: u64,
        command: Option<(f64, f64, f64)>,
        targets: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        if let Some(command) = command {
            self.set_command(command.0, command.1, command.2)?;
        }
        if let Some(targets) = targets {
            self.set_joint_targets(Some(targets))?;
        }
        let session = self.session_mut()?;
        if let Some(failure) = session.failure() {
            return Err(DivergedError::new_err(failure.to_string()));
        }
        // the GIL released while stepping: other Python threads run their own simulations
        let taken = py.detach(|| session.advance(n));
        if let Some(failure) = session.failure() {
            return Err(DivergedError::new_err(failure.to_string()));
        }
        if session.stopped() {
            // an output's error (finishing says which and names the files still written), or
            // the run's own end (its fall, in a scenario that stops at one)
            self.finish()?;
        }
        Ok(taken)
    }

    /// Steers the gait with this velocity command from the next step on (forward and sideways
    /// in m/s, turn in °/s), in place of the scenario's command schedule.
    #[pyo3(signature = (forward=0.0, sideways=0.0, turn_deg_s=0.0))]
    fn set_command(&mut self, forward: f64, sideways: f64, turn_deg_s: f64) -> PyResult<()> {
        if ![forward, sideways, turn_deg_s]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(error(format!(
                "command: forward {forward}, sideways {sideways}, turn {turn_deg_s} °/s: \
                 expected finite numbers"
            )));
        }
        self.session_mut()?.set_command(Some(VelocityCommand {
            forward,
            sideways,
            yaw_rate: turn_deg_s.to_radians(),
        }));
        Ok(())
    }

    /// Drives the servos to these joint targets (rad, in `joint_names` order) from the next
    /// step on, instead of the gait; None hands the joints back to the gait.
    #[pyo3(signature = (targets))]
    fn set_joint_targets(&mut self, targets: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let targets = match targets {
            None => None,
            Some(t) => Some(match t.extract::<PyReadonlyArray1<'_, f64>>() {
                Ok(array) => array.as_slice().map_err(error)?.to_vec(),
                Err(_) => t.extract::<Vec<f64>>().map_err(|_| {
                    error("joint targets: expected a sequence or 1-D array of numbers (rad)")
                })?,
            }),
        };
        self.session_mut()?
            .set_joint_targets(targets)
            .map_err(error)
    }

    /// The latest step's state, as NumPy arrays (world frame, SI units): time, step,
    /// body_position, body_quaternion (x, y, z, w), body_rpy (roll, pitch, yaw), body_velocity,
    /// body_angular_velocity, body_height (of the hips' plane above the ground), joint_angles,
    /// joint_velocities, joint_targets, joint_torques (one per joint), foot_positions (6×3),
    /// foot_forces (6×3, the ground's force on each foot), foot_contact (6, bool),
    /// foot_penetration (6, m; 0 off the ground), settling (still standing before the walk).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let session = self.session()?;
        let out = PyDict::new(py);
        let Some(sample) = session.sample() else {
            return Err(error("no state yet: take a step first"));
        };
        let r = &sample.robot;
        let v3 = |v: glam::DVec3| [v.x, v.y, v.z];
        let array = |values: &[f64]| PyArray1::from_slice(py, values);
        out.set_item("time", r.time)?;
        out.set_item("step", r.step)?;
        out.set_item("settling", sample.settling)?;
        out.set_item("body_position", array(&v3(r.body.translation)))?;
        let q = r.body_rotation;
        out.set_item("body_quaternion", array(&[q.x, q.y, q.z, q.w]))?;
        let (roll, pitch, yaw) = r.roll_pitch_yaw();
        out.set_item("body_rpy", array(&[roll, pitch, yaw]))?;
        out.set_item("body_velocity", array(&v3(r.body_velocity)))?;
        out.set_item("body_angular_velocity", array(&v3(r.body_angular_velocity)))?;
        out.set_item("body_height", r.body_height)?;
        out.set_item("joint_angles", array(&r.joint_angles))?;
        out.set_item("joint_velocities", array(&r.joint_velocities))?;
        out.set_item("joint_targets", array(&r.joint_targets))?;
        out.set_item("joint_torques", array(&r.joint_torques))?;
        let feet: Vec<f64> = r.foot_positions.iter().flat_map(|p| v3(*p)).collect();
        out.set_item("foot_positions", array(&feet).reshape([6, 3])?)?;
        let forces: Vec<f64> = r
            .foot_contacts
            .iter()
            .flat_map(|c| c.map_or([0.0; 3], |c| v3(c.force)))
            .collect();
        out.set_item("foot_forces", array(&forces).reshape([6, 3])?)?;
        let contact: Vec<bool> = r.foot_contacts.iter().map(Option::is_some).collect();
        out.set_item("foot_contact", PyArray1::from_vec(py, contact))?;
        let depth: Vec<f64> = r
            .foot_contacts
            .iter()
            .map(|c| c.map_or(0.0, |c| c.penetration))
            .collect();
        out.set_item("foot_penetration", array(&depth))?;
        Ok(out)
    }

    /// The metrics of `hexsim run --metrics` (a dict): of the walk so far, or of the finished
    /// run after `close`.
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match (&self.session, &self.final_metrics) {
            (Some(session), _) => {
                json_to_py(py, &serde_json::to_value(session.metrics()).map_err(error)?)
            }
            (None, Some(metrics)) => json_to_py(py, metrics),
            (None, None) => Err(error("no metrics: the simulation has not run")),
        }
    }

    /// Finishes the run: writes the files asked for (recording, trajectory, metrics) and returns
    /// their paths. `metrics()` then gives the finished run's, `complete` if it took every step.
    fn close(&mut self) -> PyResult<Vec<PathBuf>> {
        self.finish()
    }

    /// The servos' mechanical work so far (J; the metrics' `servo_energy`), without building
    /// the whole metrics dict: what an environment's reward reads every action.
    #[getter]
    fn servo_energy(&self) -> PyResult<f64> {
        Ok(self.session()?.metrics().servo_energy)
    }

    /// Steps left of the scenario's settle time and duration.
    #[getter]
    fn remaining(&self) -> PyResult<u64> {
        Ok(self.session()?.remaining())
    }

    /// Steps taken since the start (or the last reset).
    #[getter]
    fn steps(&self) -> PyResult<u64> {
        Ok(self.session()?.steps())
    }

    /// The step (s).
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.session()?.walker().hexapod().dt())
    }

    /// Seconds since the start.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.session()?.walker().hexapod().time())
    }

    /// Seconds the robot stands before the gait starts (the scenario's settle time).
    #[getter]
    fn settle_time(&self) -> PyResult<f64> {
        Ok(self.session()?.walker().settle_time())
    }

    /// The joints' names, in the order of every per-joint array and of `targets`.
    #[getter]
    fn joint_names(&self) -> PyResult<Vec<String>> {
        let model = self.session()?.walker().hexapod().model();
        Ok(model.joints.iter().map(|j| j.name.clone()).collect())
    }

    /// Each joint's (lower, upper) limit (rad), as a (joints × 2) array.
    #[getter]
    fn joint_limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let model = self.session()?.walker().hexapod().model();
        let limits: Vec<f64> = model
            .joints
            .iter()
            .flat_map(|j| [j.lower, j.upper])
            .collect();
        let n = model.joints.len();
        Ok(PyArray1::from_vec(py, limits).reshape([n, 2])?.into_any())
    }

    /// The legs as gait files name them (lf, lm, lr, rf, rm, rr), in the order of every per-foot
    /// array.
    #[getter]
    fn leg_names(&self) -> PyResult<Vec<&'static str>> {
        let model = self.session()?.walker().hexapod().model();
        Ok(model.legs.iter().map(|l| l.name).collect())
    }

    /// The robot's mass (kg).
    #[getter]
    fn mass(&self) -> PyResult<f64> {
        Ok(self.session()?.walker().hexapod().model().total_mass())
    }

    /// The scenario's name.
    #[getter]
    fn name(&self) -> String {
        self.current().name.clone()
    }

    /// The terrain generator's seed in use, if the terrain has one.
    #[getter]
    fn seed(&self) -> Option<u32> {
        self.current().seed
    }

    /// Why the simulation diverged, if it did.
    #[getter]
    fn failure(&self) -> Option<String> {
        self.session
            .as_ref()
            .and_then(|s| s.failure().map(str::to_string))
    }

    /// What is doubtful but allowed in the scenario (a missing visual mesh, fitted limits, …).
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, &self.current().warnings)
    }

    /// What hexsim chose that the scenario left out (a smaller step for light legs).
    #[getter]
    fn notes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, &self.current().notes)
    }
}

/// Steps several simulations at once, each on a thread of its own (up to `threads`, default:
/// the machine's cores), the GIL released: `steps` is one count for all or one per simulation.
/// Returns the steps each took. Each world is stepped exactly as `Simulation.step` would step it,
/// so the results are the same bit for bit, whatever the threads. A simulation that diverges
/// stops without raising (see its `failure`); one that has diverged already takes no step.
#[pyfunction]
#[pyo3(signature = (simulations, steps=None, *, threads=None))]
fn step_many(
    py: Python<'_>,
    mut simulations: Vec<PyRefMut<'_, Simulation>>,
    steps: Option<&Bound<'_, PyAny>>,
    threads: Option<usize>,
) -> PyResult<Vec<u64>> {
    let n = simulations.len();
    let counts: Vec<u64> = match steps {
        None => vec![1; n],
        Some(s) => match s.extract::<u64>() {
            Ok(k) => vec![k; n],
            Err(_) => s
                .extract::<Vec<u64>>()
                .map_err(|_| error("steps: expected a count of steps, or one per simulation"))?,
        },
    };
    if counts.len() != n {
        return Err(error(format!(
            "steps: {} counts for {n} simulations; give one count, or one per simulation",
            counts.len()
        )));
    }
    if threads == Some(0) {
        return Err(error("threads: expected at least 1"));
    }
    let mut sessions = Vec::with_capacity(n);
    for (i, sim) in simulations.iter_mut().enumerate() {
        let session = sim.session.as_mut().ok_or_else(|| {
            error(format!(
                "simulation {i} is closed: call reset() to start it again"
            ))
        })?;
        sessions.push(session);
    }
    let threads = threads.unwrap_or_else(pool::cores);
    let taken = py.detach(|| advance_all(&mut sessions, &counts, threads));
    for sim in &mut simulations {
        sim.finish_if_stopped()?;
    }
    Ok(taken)
}

/// Advances `sessions[i]` by `counts[i]` steps on up to `threads` threads (the worlds' pool);
/// returns the steps each took. A diverged session takes none.
fn advance_all(sessions: &mut [&mut WalkSession], counts: &[u64], threads: usize) -> Vec<u64> {
    let mut worlds: Vec<(&mut WalkSession, u64, u64)> = sessions
        .iter_mut()
        .zip(counts)
        .map(|(session, &count)| (&mut **session, count, 0))
        .collect();
    pool::for_each(&mut worlds, threads, |(session, count, taken)| {
        if session.failure().is_none() {
            *taken = session.advance(*count);
        }
    });
    worlds.into_iter().map(|(_, _, taken)| taken).collect()
}

#[pymodule]
fn _hexsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(step_many, m)?)?;
    m.add_class::<env::Task>()?;
    m.add_function(wrap_pyfunction!(env::step_tasks, m)?)?;
    m.add("HexsimError", m.py().get_type::<HexsimError>())?;
    m.add("DivergedError", m.py().get_type::<DivergedError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
