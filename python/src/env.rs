//! The Gymnasium environments' work on a world, in Rust: the action applied, the physics stepped
//! (or the world reset and stood through its settle time), then the observation, reward and
//! episode ends read; for one world ([`Task::step`], [`Task::reset`]) or for many at once on the
//! worlds' thread pool ([`step_tasks`]), the GIL released.
//!
//! `HexapodEnv` and `HexapodVectorEnv` both go through [`Task::step_world`] and
//! [`Task::reset_world`], so N worlds of the vector environment equal N single environments bit
//! for bit by construction. Done in Python, this work cost the vector environment some 50–100 µs
//! per world and action, serially, against ~400 µs of physics stepped in parallel.

use crate::{Simulation, error, pool};
use hexsim::gait::VelocityCommand;
use hexsim::runner::walk::WalkSession;
use hexsim::sim::walker::WalkSample;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The feet whose contacts are observed.
const FEET: usize = 6;

/// How an action (each component in [-1, 1], clipped there) drives the robot.
enum Drive {
    /// The joints' targets: offsets from the standing pose, the action × `scale` (rad), clipped to
    /// each joint's (lower, upper) limits.
    Joints { scale: f64, limits: Vec<(f64, f64)> },
    /// The gait's velocity command: the action × `max_command` (forward m/s, sideways m/s, turn
    /// °/s).
    Gait { max_command: [f64; 3] },
}

/// What an action earned a world.
#[derive(Default)]
struct Outcome {
    reward: f64,
    terminated: bool,
    truncated: bool,
    /// The servos' mechanical work over the action (J).
    work: f64,
    /// The body's x after it (m).
    x: f64,
    /// Why the simulation diverged, if it has.
    diverged: Option<String>,
}

/// A Gymnasium environment's task on one `Simulation`: how an action drives it, what it observes,
/// what it earns and when its episode ends (see `hexsim.env`), and the episode's bookkeeping.
///
/// `Task(simulation, action, frame_skip, *, action_scale, max_command, energy_weight, fall_tilt)`:
/// `action` is `"joints"` or `"gait"`; `fall_tilt` in radians.
#[pyclass(module = "hexsim._hexsim")]
pub(crate) struct Task {
    drive: Drive,
    /// Steps per action.
    frame_skip: u64,
    /// The reward's price of a joule of servo work (m/J).
    energy_weight: f64,
    /// Roll or pitch beyond which the robot has fallen (rad).
    fall_tilt: f64,
    joints: usize,
    /// The gait's standing pose at the end of the episode's settle time: the joint action's
    /// centre.
    standing: Vec<f64>,
    /// The body's x and the servos' work so far, after the last action: the reward's baselines.
    x: f64,
    energy: f64,
}

impl Task {
    fn action_size(&self) -> usize {
        match self.drive {
            Drive::Joints { .. } => self.joints,
            Drive::Gait { .. } => 3,
        }
    }

    /// Roll, pitch, velocity (3), angular velocity (3), the hips' height, the joints' angles and
    /// velocities, the feet's contacts.
    fn observation_size(&self) -> usize {
        2 + 3 + 3 + 1 + 2 * self.joints + FEET
    }

    /// Restarts the world on the terrain of `seed`, stands it through the settle time and starts
    /// the episode's bookkeeping; writes the first observation into `obs`. A divergence while
    /// standing is left for the caller to read (the simulation's `failure`).
    fn reset_world(&mut self, sim: &mut Simulation, seed: u32, obs: &mut [f64]) -> PyResult<()> {
        sim.reset(Some(seed))?;
        let settle = settle_steps(sim.session()?);
        sim.session_mut()?.advance(settle);
        sim.finish_if_stopped()?;
        let session = sim.session()?;
        let robot = &last_sample(session)?.robot;
        self.standing.clone_from(&robot.joint_targets);
        self.x = robot.body.translation.x;
        self.energy = session.metrics().servo_energy;
        observe(session, obs)
    }

    /// Applies `action`, steps `frame_skip` steps (none once diverged), writes the observation
    /// into `obs` and returns what the action earned.
    fn step_world(
        &mut self,
        sim: &mut Simulation,
        action: &[f64],
        obs: &mut [f64],
    ) -> PyResult<Outcome> {
        let session = sim.session_mut()?;
        self.act(session, action)?;
        if session.failure().is_none() {
            session.advance(self.frame_skip);
        }
        sim.finish_if_stopped()?;
        let session = sim.session()?;
        let outcome = self.outcome(session)?;
        observe(session, obs)?;
        Ok(outcome)
    }

    /// Sets the joints' targets or the gait's command from the action (no NaN: checked before),
    /// clipped as NumPy's `clip` would (to the joint limits `max` then `min`, not `clamp`, so that
    /// limits given the wrong way round cannot panic).
    fn act(&self, session: &mut WalkSession, action: &[f64]) -> PyResult<()> {
        let clipped = action.iter().map(|a| a.clamp(-1.0, 1.0));
        match &self.drive {
            Drive::Joints { scale, limits } => {
                let targets = clipped
                    .zip(&self.standing)
                    .zip(limits)
                    .map(|((a, standing), &(lower, upper))| {
                        (standing + scale * a).max(lower).min(upper)
                    })
                    .collect();
                session.set_joint_targets(Some(targets)).map_err(error)
            }
            Drive::Gait { max_command } => {
                let mut command = [0.0; 3];
                for ((c, a), max) in command.iter_mut().zip(clipped).zip(max_command) {
                    *c = a * max;
                }
                session.set_command(Some(VelocityCommand {
                    forward: command[0],
                    sideways: command[1],
                    yaw_rate: command[2].to_radians(),
                }));
                Ok(())
            }
        }
    }

    /// The reward (forward progress less the priced servo work), the episode's ends, and the
    /// baselines moved on to now.
    fn outcome(&mut self, session: &WalkSession) -> PyResult<Outcome> {
        let diverged = session.failure().map(str::to_string);
        let energy = session.metrics().servo_energy;
        let work = energy - self.energy;
        self.energy = energy;
        let robot = &last_sample(session)?.robot;
        let x = robot.body.translation.x;
        let reward = (x - self.x) - self.energy_weight * work;
        self.x = x;
        let (roll, pitch, _) = robot.roll_pitch_yaw();
        let fallen = roll.abs().max(pitch.abs()) > self.fall_tilt;
        let terminated = fallen || diverged.is_some();
        let truncated = !terminated && session.remaining() == 0;
        Ok(Outcome {
            reward,
            terminated,
            truncated,
            work,
            x,
            diverged,
        })
    }
}

/// The steps that stand the robot through the scenario's settle time, at least one so that there
/// is a state to observe (rounded as Python's `round`, half to even, as the environments did).
fn settle_steps(session: &WalkSession) -> u64 {
    let walker = session.walker();
    (walker.settle_time() / walker.hexapod().dt())
        .round_ties_even()
        .max(1.0) as u64
}

fn last_sample(session: &WalkSession) -> PyResult<&WalkSample> {
    session
        .sample()
        .ok_or_else(|| error("no state yet: take a step first"))
}

/// Writes the observation of the latest step into `obs` (the task's observation size).
fn observe(session: &WalkSession, obs: &mut [f64]) -> PyResult<()> {
    let r = &last_sample(session)?.robot;
    let (roll, pitch, _) = r.roll_pitch_yaw();
    let (v, w) = (r.body_velocity, r.body_angular_velocity);
    let body = [roll, pitch, v.x, v.y, v.z, w.x, w.y, w.z, r.body_height];
    let contacts = r
        .foot_contacts
        .iter()
        .map(|c| if c.is_some() { 1.0 } else { 0.0 });
    let values = body
        .into_iter()
        .chain(r.joint_angles.iter().copied())
        .chain(r.joint_velocities.iter().copied())
        .chain(contacts);
    let mut written = 0;
    for (o, value) in obs.iter_mut().zip(values) {
        *o = value;
        written += 1;
    }
    if written != obs.len() {
        return Err(error(format!(
            "observation: {written} values for {} places",
            obs.len()
        )));
    }
    Ok(())
}

/// A shape as Python writes it: `(18,)`, `(2, 18)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The actions, one row per world, copied out of NumPy's memory (Python may change the array
/// while the GIL is released). Refused, before any world moves, when their shape is not `shape`
/// or one is NaN; an infinite one is clipped as any beyond [-1, 1].
fn checked_actions(actions: &PyReadonlyArrayDyn<'_, f64>, shape: &[usize]) -> PyResult<Vec<f64>> {
    if actions.shape() != shape {
        return Err(PyValueError::new_err(format!(
            "action: shape {}, expected {}",
            shape_text(actions.shape()),
            shape_text(shape)
        )));
    }
    let values: Vec<f64> = actions.as_array().iter().copied().collect();
    if let Some(i) = values.iter().position(|a| a.is_nan()) {
        let size = shape.last().copied().unwrap_or(1).max(1);
        let place = match shape {
            [_, _] => format!("world {}'s action, component {}", i / size, i % size),
            _ => format!("component {i}"),
        };
        return Err(PyValueError::new_err(format!(
            "action: NaN in {place}; expected numbers in [-1, 1]"
        )));
    }
    Ok(values)
}

#[pymethods]
impl Task {
    #[new]
    #[pyo3(signature = (simulation, action, frame_skip, *, action_scale, max_command, energy_weight, fall_tilt))]
    fn new(
        simulation: PyRef<'_, Simulation>,
        action: &str,
        frame_skip: u64,
        action_scale: f64,
        max_command: (f64, f64, f64),
        energy_weight: f64,
        fall_tilt: f64,
    ) -> PyResult<Self> {
        let model = simulation.session()?.walker().hexapod().model();
        let joints = model.joints.len();
        let drive = match action {
            "joints" => Drive::Joints {
                scale: action_scale,
                limits: model.joints.iter().map(|j| (j.lower, j.upper)).collect(),
            },
            "gait" => Drive::Gait {
                max_command: [max_command.0, max_command.1, max_command.2],
            },
            _ => {
                return Err(PyValueError::new_err(format!(
                    "action: '{action}', expected 'joints' or 'gait'"
                )));
            }
        };
        if frame_skip == 0 || joints == 0 {
            return Err(PyValueError::new_err(format!(
                "frame_skip {frame_skip}, joints {joints}: expected at least 1 of each"
            )));
        }
        Ok(Task {
            drive,
            frame_skip,
            energy_weight,
            fall_tilt,
            joints,
            standing: vec![0.0; joints],
            x: 0.0,
            energy: 0.0,
        })
    }

    /// Restarts `simulation` on the terrain of `seed` and stands it through its settle time;
    /// returns the first observation.
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        mut simulation: PyRefMut<'_, Simulation>,
        seed: u32,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let mut obs = vec![0.0; self.observation_size()];
        let sim = &mut *simulation;
        py.detach(|| self.reset_world(sim, seed, &mut obs))?;
        Ok(PyArray1::from_vec(py, obs))
    }

    /// Applies `action` (1-D, float64) and steps `simulation` one action's steps; returns the
    /// observation, reward, terminated, truncated, the servos' work, the body's x and why the
    /// simulation diverged (None if it has not).
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        mut simulation: PyRefMut<'_, Simulation>,
        action: PyReadonlyArrayDyn<'_, f64>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        f64,
        bool,
        bool,
        f64,
        f64,
        Option<String>,
    )> {
        let action = checked_actions(&action, &[self.action_size()])?;
        let mut obs = vec![0.0; self.observation_size()];
        let sim = &mut *simulation;
        let o = py.detach(|| self.step_world(sim, &action, &mut obs))?;
        let obs = PyArray1::from_vec(py, obs);
        Ok((
            obs,
            o.reward,
            o.terminated,
            o.truncated,
            o.work,
            o.x,
            o.diverged,
        ))
    }

    /// The length of an action.
    #[getter(action_size)]
    fn py_action_size(&self) -> usize {
        self.action_size()
    }

    /// The length of an observation.
    #[getter(observation_size)]
    fn py_observation_size(&self) -> usize {
        self.observation_size()
    }

    /// The gait's standing pose at the end of the episode's settle time (rad, per joint): the
    /// centre of the joint action.
    #[getter]
    fn standing<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.standing)
    }
}

/// One world's share of a [`step_tasks`] call, and its result.
struct World<'a> {
    sim: &'a mut Simulation,
    task: &'a mut Task,
    action: &'a [f64],
    /// Some: reset on this terrain seed instead of stepping.
    seed: Option<u32>,
    obs: &'a mut [f64],
    result: PyResult<Outcome>,
}

impl World<'_> {
    fn run(&mut self) {
        self.result = match self.seed {
            Some(seed) => self
                .task
                .reset_world(self.sim, seed, self.obs)
                .map(|()| Outcome::default()),
            None => self.task.step_world(self.sim, self.action, self.obs),
        };
    }
}

/// The observations (worlds × observation size), rewards, terminated, truncated, the servos'
/// work, the bodies' x, and why each world diverged (None if it has not).
type Results<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Vec<Option<String>>,
);

/// Steps many environments' worlds at once, each on a thread of its own (up to `threads`,
/// default: the machine's cores), the GIL released: world `i` (`simulations[i]` with
/// `tasks[i]`) takes `actions[i]` (a float64 array, worlds × action size) and steps one action's
/// steps — or, where `seeds[i]` is a seed, is reset on that terrain and stood through its settle
/// time instead (reward 0, not ended). Returns the observations (worlds × observation size),
/// rewards, terminated, truncated, the servos' work (0 for a reset), the bodies' x (0 for a
/// reset) and why each world diverged (None if it has not). Each world is worked exactly as
/// `Task.step`/`Task.reset` would, so the results are the same bit for bit, whatever the threads.
#[pyfunction]
#[pyo3(signature = (simulations, tasks, actions, seeds, *, threads=None))]
pub(crate) fn step_tasks<'py>(
    py: Python<'py>,
    mut simulations: Vec<PyRefMut<'py, Simulation>>,
    mut tasks: Vec<PyRefMut<'py, Task>>,
    actions: PyReadonlyArrayDyn<'py, f64>,
    seeds: Vec<Option<u32>>,
    threads: Option<usize>,
) -> PyResult<Results<'py>> {
    let n = simulations.len();
    if n == 0 || tasks.len() != n || seeds.len() != n {
        return Err(error(format!(
            "{n} simulations, {} tasks, {} seeds: expected at least one of each, as many of each",
            tasks.len(),
            seeds.len()
        )));
    }
    if threads == Some(0) {
        return Err(error("threads: expected at least 1"));
    }
    let (k, d) = (tasks[0].action_size(), tasks[0].observation_size());
    if tasks
        .iter()
        .any(|t| t.action_size() != k || t.observation_size() != d)
    {
        return Err(error(
            "tasks: expected the same action and observation sizes",
        ));
    }
    for (i, (sim, seed)) in simulations.iter().zip(&seeds).enumerate() {
        if seed.is_none() && sim.session.is_none() {
            return Err(error(format!(
                "simulation {i} is closed: call reset() to start it again"
            )));
        }
    }
    let actions = checked_actions(&actions, &[n, k])?;
    let mut obs = vec![0.0; n * d];
    let mut worlds: Vec<World<'_>> = simulations
        .iter_mut()
        .zip(tasks.iter_mut())
        .zip(actions.chunks(k))
        .zip(&seeds)
        .zip(obs.chunks_mut(d))
        .map(|((((sim, task), action), &seed), obs)| World {
            sim,
            task,
            action,
            seed,
            obs,
            result: Ok(Outcome::default()),
        })
        .collect();
    py.detach(|| pool::for_each(&mut worlds, threads.unwrap_or_else(pool::cores), World::run));
    let mut outcomes = Vec::with_capacity(n);
    for (i, world) in worlds.into_iter().enumerate() {
        outcomes.push(world.result.map_err(|e| {
            let err = error(format!("world {i}: {}", e.value(py)));
            err.set_cause(py, Some(e));
            err
        })?);
    }
    let column = |f: fn(&Outcome) -> f64| PyArray1::from_iter(py, outcomes.iter().map(f));
    let flag = |f: fn(&Outcome) -> bool| PyArray1::from_iter(py, outcomes.iter().map(f));
    Ok((
        PyArray1::from_vec(py, obs).reshape([n, d])?.into_any(),
        column(|o| o.reward),
        flag(|o| o.terminated),
        flag(|o| o.truncated),
        column(|o| o.work),
        column(|o| o.x),
        outcomes.into_iter().map(|o| o.diverged).collect(),
    ))
}
