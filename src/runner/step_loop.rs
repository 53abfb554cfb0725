//! The one step loop every run goes through: step the simulation, check it has not left physics
//! (the watchdog), hand the sample to the observers; stop early on divergence, on an observer's
//! error, when interrupted or when the run's own end comes (a walk's fall, where its scenario
//! stops at one), and finish every observer either way, so each file holds the run as far as it
//! went.

use crate::record::Observer;
use anyhow::Result;
use std::path::PathBuf;

/// A simulation the loop can drive.
pub trait Stepper {
    type Sample: crate::record::Sample;
    /// What observers may read besides the sample (e.g. the walker, for the links' poses).
    type World: ?Sized;

    /// The state before the first step, if the observers should see it (the ball's drop).
    fn initial(&self) -> Option<Self::Sample> {
        None
    }

    fn step(&mut self) -> Self::Sample;

    /// [`Stepper::step`] into `last`, the last sample, once nothing reads it any more: a
    /// stepper may write the new sample over it in place instead of making a new one (the walk's
    /// vectors of joint angles, rates, targets and torques: no allocation, no copy of the sample).
    fn step_into(&mut self, last: &mut Option<Self::Sample>) {
        *last = Some(self.step());
    }

    fn world(&self) -> &Self::World;

    /// Why `sample` is not physical, if it is not: what, where and the likely cause (see
    /// [`super::watchdog`]).
    fn diverged(&self, sample: &Self::Sample) -> Option<String>;

    /// True when `sample` ends the run before its planned steps, its result decided (a walk
    /// that stops at its fall): the run is complete there.
    fn ended(&self, _sample: &Self::Sample) -> bool {
        false
    }
}

/// How the loop ended.
pub struct LoopEnd {
    /// False when the run stopped early (interrupted or diverged); true when it took every
    /// planned step or came to its own end ([`Stepper::ended`]).
    pub complete: bool,
    /// What diverged, if the run did.
    pub failure: Option<String>,
    /// Steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the stepping (observers included, their finishing not).
    pub seconds: f64,
    /// Every file the observers wrote, in their order.
    pub written: Vec<PathBuf>,
}

/// Takes up to `steps` steps, each observed by every observer in order, then finishes them in
/// that order. An observer's error stops the run; it is returned (naming the files still written)
/// after every observer has been finished.
pub fn run<T: Stepper>(
    stepper: &mut T,
    steps: u64,
    observers: &mut [&mut dyn Observer<T::Sample, T::World>],
) -> Result<LoopEnd> {
    let mut looping = Looping::begin(stepper, observers);
    looping.advance(stepper, steps, observers);
    looping.finish(steps, observers)
}

/// The step loop taken a stretch at a time (a caller that steps, reads the state, steps on, as
/// Python does): [`run`] is `begin`, one `advance` and `finish`, and so is every run in between.
pub struct Looping<S> {
    /// An observer's error: the loop takes no more steps.
    error: Option<anyhow::Error>,
    /// What diverged: the loop takes no more steps.
    failure: Option<String>,
    /// The run came to its own end ([`Stepper::ended`]): the loop takes no more steps.
    ended: bool,
    taken: u64,
    /// Wall-clock seconds spent in `advance`.
    seconds: f64,
    /// The last step's sample (or the initial state's).
    last: Option<S>,
}

impl<S> Looping<S> {
    /// Shows the observers the initial state, if the stepper has one.
    pub fn begin<T: Stepper<Sample = S>>(
        stepper: &T,
        observers: &mut [&mut dyn Observer<S, T::World>],
    ) -> Self {
        let last = stepper.initial();
        let error = last
            .as_ref()
            .and_then(|initial| observe(observers, initial, stepper.world()).err());
        Looping {
            error,
            failure: None,
            ended: false,
            taken: 0,
            seconds: 0.0,
            last,
        }
    }

    /// Takes up to `steps` more steps, each observed; fewer if the run diverges, an observer
    /// fails, it comes to its own end or the process is interrupted. Returns the steps taken.
    pub fn advance<T: Stepper<Sample = S>>(
        &mut self,
        stepper: &mut T,
        steps: u64,
        observers: &mut [&mut dyn Observer<S, T::World>],
    ) -> u64 {
        let started = std::time::Instant::now();
        let mut taken = 0;
        while !self.stopped() && taken < steps && !super::interrupted() {
            stepper.step_into(&mut self.last);
            let sample = self.last.as_ref().expect("a step leaves its sample");
            taken += 1;
            if let Some(message) = stepper.diverged(sample) {
                // the diverged step is still observed: the files show where it went wrong
                let _ = observe(observers, sample, stepper.world());
                self.failure = Some(message);
            } else {
                self.error = observe(observers, sample, stepper.world()).err();
                self.ended = stepper.ended(sample);
            }
        }
        self.taken += taken;
        self.seconds += started.elapsed().as_secs_f64();
        taken
    }

    /// True once the loop will take no more steps: diverged, an observer failed or the run came
    /// to its own end.
    pub fn stopped(&self) -> bool {
        self.error.is_some() || self.failure.is_some() || self.ended
    }

    /// What diverged, if the run did.
    pub fn failure(&self) -> Option<&str> {
        self.failure.as_deref()
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.taken
    }

    /// The latest state: the last step's sample, or the initial one before any step.
    pub fn last(&self) -> Option<&S> {
        self.last.as_ref()
    }

    /// Finishes every observer in order; the run is complete if it took `planned` steps or came
    /// to its own end, and neither diverged nor failed.
    pub fn finish<W: ?Sized>(
        self,
        planned: u64,
        observers: &mut [&mut dyn Observer<S, W>],
    ) -> Result<LoopEnd> {
        let complete =
            (self.taken == planned || self.ended) && self.error.is_none() && self.failure.is_none();
        let mut written = Vec::new();
        let mut finish_error = None;
        for observer in observers.iter_mut() {
            // once a file failed (a full disk), what follows (the metrics) says incomplete
            match observer.finish(complete && finish_error.is_none()) {
                Ok(file) => written.extend(file),
                Err(e) => {
                    finish_error.get_or_insert(e);
                }
            }
        }
        // a writer's own error says more than the observe error it caused ("the writer stopped")
        if let Some(e) = finish_error.or(self.error) {
            return Err(super::failure_error(&format!("{e:#}"), &written));
        }
        Ok(LoopEnd {
            complete,
            failure: self.failure,
            steps: self.taken,
            seconds: self.seconds,
            written,
        })
    }
}

fn observe<S, W: ?Sized>(
    observers: &mut [&mut dyn Observer<S, W>],
    sample: &S,
    world: &W,
) -> Result<()> {
    observers
        .iter_mut()
        .try_for_each(|o| o.observe(sample, world))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Sample;
    use std::sync::{Arc, Mutex};

    struct Count(u64);

    impl Sample for Count {
        fn step(&self) -> u64 {
            self.0
        }
    }

    /// Counts up; "diverges" at `diverge_at`, comes to its own end at `end_at`.
    struct Counter {
        n: u64,
        diverge_at: u64,
        initial: bool,
        end_at: u64,
    }

    impl Stepper for Counter {
        type Sample = Count;
        type World = ();
        fn initial(&self) -> Option<Count> {
            self.initial.then_some(Count(0))
        }
        fn step(&mut self) -> Count {
            self.n += 1;
            Count(self.n)
        }
        fn world(&self) -> &() {
            &()
        }
        fn diverged(&self, s: &Count) -> Option<String> {
            (s.0 == self.diverge_at).then(|| format!("diverged at {}", s.0))
        }
        fn ended(&self, s: &Count) -> bool {
            s.0 == self.end_at
        }
    }

    /// Logs what it saw into a shared list; fails at `fail_at`.
    struct Log {
        name: &'static str,
        seen: Arc<Mutex<Vec<String>>>,
        fail_at: Option<u64>,
    }

    impl Observer<Count, ()> for Log {
        fn observe(&mut self, s: &Count, _: &()) -> Result<()> {
            self.seen
                .lock()
                .unwrap()
                .push(format!("{} {}", self.name, s.0));
            if self.fail_at == Some(s.0) {
                anyhow::bail!("{} cannot write", self.name);
            }
            Ok(())
        }
        fn finish(&mut self, complete: bool) -> Result<Option<PathBuf>> {
            self.seen
                .lock()
                .unwrap()
                .push(format!("{} finished {complete}", self.name));
            Ok(Some(PathBuf::from(self.name)))
        }
    }

    fn logs(seen: &Arc<Mutex<Vec<String>>>, fail_at: Option<u64>) -> (Log, Log) {
        let log = |name| Log {
            name,
            seen: seen.clone(),
            fail_at: None,
        };
        (
            log("a"),
            Log {
                fail_at,
                ..log("b")
            },
        )
    }

    #[test]
    fn a_complete_run_observes_every_step_in_order_then_finishes_each() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let (mut a, mut b) = logs(&seen, None);
        let mut counter = Counter {
            n: 0,
            diverge_at: 0,
            initial: true,
            end_at: 0,
        };
        let end = run(&mut counter, 2, &mut [&mut a, &mut b]).unwrap();
        assert!(end.complete && end.failure.is_none());
        assert_eq!(end.steps, 2);
        assert_eq!(end.written, [PathBuf::from("a"), PathBuf::from("b")]);
        let expected = ["a 0", "b 0", "a 1", "b 1", "a 2", "b 2"];
        let mut expected: Vec<String> = expected.map(String::from).to_vec();
        expected.extend(["a finished true".into(), "b finished true".into()]);
        assert_eq!(*seen.lock().unwrap(), expected);
    }

    /// A walk that stops at its fall: the fall's step observed, no step after it, and the run
    /// complete (its result decided), not cut short.
    #[test]
    fn a_run_that_comes_to_its_own_end_stops_there_complete() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let (mut a, mut b) = logs(&seen, None);
        let mut counter = Counter {
            n: 0,
            diverge_at: 0,
            initial: false,
            end_at: 3,
        };
        let end = run(&mut counter, 10, &mut [&mut a, &mut b]).unwrap();
        assert!(end.complete && end.failure.is_none());
        assert_eq!(end.steps, 3);
        let seen = seen.lock().unwrap();
        assert_eq!(
            seen[4..],
            ["a 3", "b 3", "a finished true", "b finished true"]
        );
    }

    #[test]
    fn the_diverged_step_is_observed_and_every_file_finished_incomplete() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let (mut a, mut b) = logs(&seen, None);
        let mut counter = Counter {
            n: 0,
            diverge_at: 3,
            initial: false,
            end_at: 0,
        };
        let end = run(&mut counter, 10, &mut [&mut a, &mut b]).unwrap();
        assert!(!end.complete);
        assert_eq!(end.failure.as_deref(), Some("diverged at 3"));
        assert_eq!(end.steps, 3);
        let seen = seen.lock().unwrap();
        assert_eq!(
            seen[4..],
            ["a 3", "b 3", "a finished false", "b finished false"]
        );
    }

    #[test]
    fn an_observer_error_stops_the_run_finishes_the_others_and_names_their_files() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let (mut a, mut b) = logs(&seen, Some(2));
        let mut counter = Counter {
            n: 0,
            diverge_at: 0,
            initial: false,
            end_at: 0,
        };
        let error = run(&mut counter, 10, &mut [&mut a, &mut b])
            .err()
            .expect("b's error is the run's");
        let message = format!("{error:#}");
        assert!(message.contains("b cannot write"), "{message}");
        assert!(message.contains("files written: a, b"), "{message}");
        let seen = seen.lock().unwrap();
        assert_eq!(
            seen[seen.len() - 2..],
            ["a finished false", "b finished false"]
        );
        assert!(
            !seen.contains(&"a 3".to_string()),
            "stepped on after the error"
        );
    }
}
