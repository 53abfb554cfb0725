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

/// The robots built in, by name (`--robot hex18`, `robot = "hex18"`): the reference alone.
pub const ROBOTS: &[(&str, Builtin)] = &[("hex18", HEX18)];

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

macro_rules! builtin {
    ($dir:literal, $name:literal) => {
        (
            $name,
            Builtin {
                path: concat!($dir, "/", $name, ".toml"),
                text: include_str!(concat!("../../", $dir, "/", $name, ".toml")),
            },
        )
    };
}

/// The gaits of `gaits/`, by name: `--gait wave` works from any folder.
pub const GAITS: &[(&str, Builtin)] = &[
    builtin!("gaits", "tripod"),
    builtin!("gaits", "ripple"),
    builtin!("gaits", "wave"),
];

/// The terrains of `terrains/` that need no other file, by name: `--terrain flat` works from any
/// folder (`natural_matlab` reads its CSV beside it, so it is not among them).
pub const TERRAINS: &[(&str, Builtin)] = &[
    builtin!("terrains", "bell"),
    builtin!("terrains", "discrete_obstacles"),
    builtin!("terrains", "flat"),
    builtin!("terrains", "gaps"),
    builtin!("terrains", "natural"),
    builtin!("terrains", "natural_ball"),
    builtin!("terrains", "natural_long"),
    builtin!("terrains", "pyramid_stairs"),
    builtin!("terrains", "rough"),
    builtin!("terrains", "sine"),
    builtin!("terrains", "slope15"),
    builtin!("terrains", "stairs"),
    builtin!("terrains", "stepping_stones"),
    builtin!("terrains", "steps"),
    builtin!("terrains", "steps_down"),
];

/// The terrain ladder's families (`ladder/`), by name: `hexsim ladder` runs them from any
/// folder, and `hexsim ladder stairs_up` one of them.
pub const LADDER: &[(&str, Builtin)] = &[
    builtin!("ladder", "gaps"),
    builtin!("ladder", "obstacles"),
    builtin!("ladder", "pyramid"),
    builtin!("ladder", "rough"),
    builtin!("ladder", "slope_down"),
    builtin!("ladder", "slope_up"),
    builtin!("ladder", "stairs_down"),
    builtin!("ladder", "stairs_up"),
    builtin!("ladder", "stones"),
];

/// The built-in file a scenario's `gait = "NAME"` or `terrain = "NAME"` names, when `file` is a
/// bare name (no folder, no extension) and `path` (where it resolves) is not a file: a file the
/// user has of that name always wins.
pub fn named(
    list: &[(&str, Builtin)],
    file: &std::path::Path,
    path: &std::path::Path,
) -> Option<Builtin> {
    if path.exists() || file.components().count() != 1 || file.extension().is_some() {
        return None;
    }
    let name = file.to_str()?;
    list.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// The names in `list`, for a message.
pub fn names(list: &[(&str, Builtin)]) -> String {
    list.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
}

/// [`not_found_hint`] as a `map_err` for a command that reads a file of `kind` at `path`.
pub fn with_hint<E: std::fmt::Display>(
    path: &std::path::Path,
    kind: &str,
    list: &[(&str, Builtin)],
) -> impl FnOnce(E) -> String {
    move |e| not_found_hint(e.to_string(), path, kind, list)
}

/// `message` for a file of `kind` that could not be read, with the built-in names of its kind
/// (`list`) when nothing is at `path`: a name mistyped, or a repository's file named from
/// elsewhere.
pub fn not_found_hint(
    message: String,
    path: &std::path::Path,
    kind: &str,
    list: &[(&str, Builtin)],
) -> String {
    if path.exists() {
        message
    } else {
        format!("{message} (built-in {kind}, by name: {})", names(list))
    }
}
