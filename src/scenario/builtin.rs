//! The files built into the binary, so that every command runs with no files at hand.

/// A built-in file: the path it has in the repository, and its text.
#[derive(Debug, Clone, Copy)]
pub struct Builtin {
    pub path: &'static str,
    pub text: &'static str,
}

/// The reference robot (docs/validation.md, *The reference*).
pub const HEX18: Builtin = Builtin {
    path: "robots/hex18.urdf",
    text: include_str!("../../robots/hex18.urdf"),
};

/// The reference robot's robot file (its stance).
pub const HEX18_FILE: Builtin = Builtin {
    path: "robots/hex18.toml",
    text: include_str!("../../robots/hex18.toml"),
};

/// The reference robot, loaded with its robot file.
pub fn hex18() -> crate::robot::RobotModel {
    crate::robot::urdf::from_str_with(HEX18.text, Some(HEX18_FILE.text), HEX18.path.as_ref())
        .expect("the built-in hex18 loads (tested)")
}

/// The tripod gait.
pub const TRIPOD: Builtin = Builtin {
    path: "gaits/tripod.toml",
    text: include_str!("../../gaits/tripod.toml"),
};

/// The paper's natural terrain at hexapod scale, 0.04 m peak to peak over 4 m × 4 m.
pub const NATURAL: Builtin = Builtin {
    path: "terrains/natural.toml",
    text: include_str!("../../terrains/natural.toml"),
};

/// The paper's natural terrain at ball scale, 0.2 m peak to peak over 4 m × 4 m.
pub const NATURAL_BALL: Builtin = Builtin {
    path: "terrains/natural_ball.toml",
    text: include_str!("../../terrains/natural_ball.toml"),
};
