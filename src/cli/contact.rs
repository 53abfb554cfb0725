//! The contact's options, shared by `run` and `ball`: the scenario's `[contact]` table on the
//! command line, with its defaults (the reference contact of shared/reference §2).

use clap::Args;
use hexsim::scenario::spec::{
    ContactSpec, FrictionChoice, NormalChoice, OrientationChoice, VariantChoice,
};

/// Contact parameters; their defaults are the scenario's (`ContactSpec::default`).
#[derive(Args)]
pub struct ContactArgs {
    /// Normal force law.
    #[arg(long, value_enum, default_value_t = ContactSpec::default().normal)]
    normal_law: NormalChoice,
    /// Normal stiffness k (N/m; for Hunt–Crossley N/mⁿ). Default: the reference 2e4 for a ball;
    /// for a walk, the reference fitted to the robot's weight (hex18's: 2e4).
    #[arg(long)]
    stiffness: Option<f64>,
    /// Normal damping c (N·s/m; for Hunt–Crossley d in s/m). Default: the reference 150 for a
    /// ball; for a walk, the reference fitted to the robot's weight (hex18's: 150).
    #[arg(long)]
    damping: Option<f64>,
    /// Hunt–Crossley exponent n.
    #[arg(long, default_value_t = ContactSpec::default().exponent)]
    hc_exponent: f64,
    /// Friction law.
    #[arg(long, value_enum, default_value_t = ContactSpec::default().friction)]
    friction: FrictionChoice,
    /// Static friction coefficient μs (Karnopp, Stribeck).
    #[arg(long, default_value_t = ContactSpec::default().mu_static)]
    mu_static: f64,
    /// Kinetic friction coefficient μk (Karnopp; Coulomb's μ; Stribeck's Coulomb level).
    #[arg(long, default_value_t = ContactSpec::default().mu_kinetic)]
    mu_kinetic: f64,
    /// Karnopp stick band Δv (m/s).
    #[arg(long, default_value_t = ContactSpec::default().stick_band)]
    stick_band: f64,
    /// Regularisation width of Coulomb and Stribeck (m/s).
    #[arg(long, default_value_t = ContactSpec::default().width)]
    friction_width: f64,
    /// Viscous friction coefficient (N·s/m; viscous law, Stribeck's viscous part).
    #[arg(long, default_value_t = ContactSpec::default().viscous)]
    viscous: f64,
    /// Stribeck velocity (m/s).
    #[arg(long, default_value_t = ContactSpec::default().stribeck_velocity)]
    stribeck_velocity: f64,
    /// How the ground's orientation is found.
    #[arg(long, value_enum, default_value_t = ContactSpec::default().orientation)]
    orientation: OrientationChoice,
    /// The paper's half-step XE = YE (m) for its finite-difference angles.
    #[arg(long, default_value_t = ContactSpec::default().paper_step)]
    paper_step: f64,
    /// Fraction of a sticking contact's drift that its stick force undoes per step (0: off, each
    /// friction law as its equation; the default halves the creep of a foot under a changing load).
    #[arg(long, default_value_t = ContactSpec::default().drift_recovery)]
    drift_recovery: f64,
    /// Rolling resistance ρ (m): a torque of at most ρ·Fn against rolling (0: none; a sphere's
    /// rolling-resistance coefficient is ρ/r).
    #[arg(long, default_value_t = ContactSpec::default().rolling_resistance)]
    rolling_resistance: f64,
    /// Spin friction μ_t (m): a torque of at most μ_t·Fn against the spin about the ground's
    /// normal (0: none; MuJoCo's torsional friction, condim 4).
    #[arg(long, default_value_t = ContactSpec::default().spin_friction)]
    spin_friction: f64,
    /// Contact model: hexsim's, or the paper's step for step (vertical penetration, its angles
    /// with --paper-step, explicit damper, friction laws unlimited, forces at the sphere's centre).
    #[arg(long, value_enum, default_value_t = ContactSpec::default().variant)]
    contact_model: VariantChoice,
}

impl ContactArgs {
    pub fn spec(&self) -> ContactSpec {
        ContactSpec {
            normal: self.normal_law,
            stiffness: self.stiffness,
            damping: self.damping,
            exponent: self.hc_exponent,
            friction: self.friction,
            mu_static: self.mu_static,
            mu_kinetic: self.mu_kinetic,
            stick_band: self.stick_band,
            width: self.friction_width,
            viscous: self.viscous,
            stribeck_velocity: self.stribeck_velocity,
            orientation: self.orientation,
            paper_step: self.paper_step,
            drift_recovery: self.drift_recovery,
            rolling_resistance: self.rolling_resistance,
            spin_friction: self.spin_friction,
            variant: self.contact_model,
        }
    }
}
