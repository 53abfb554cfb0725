//! The walking direction of a robot: its angle about z in the URDF's base link frame, and where
//! it came from (the URDF's +x, the robot file, or chosen from the legs; see `legs`). Its own
//! module so that the model (`model`) and the leg finder (`legs`) both use it without using each
//! other.

/// Where the walking direction came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForwardFrom {
    /// The URDF's +x.
    Urdf,
    /// The robot file's `forward`.
    RobotFile,
    /// Chosen from the legs: the URDF's x does not split them three a side.
    Legs,
    /// Chosen from the legs, and turned about to where their names put the front (`front_*`,
    /// `lf`/`rf`, … ahead; `rear_*`, `lr`/`rr`, `hind`, … behind).
    LegNames,
}

/// The walking direction: its angle about z in the URDF's base link frame (rad), and where it
/// came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forward {
    pub yaw: f64,
    pub from: ForwardFrom,
}

impl Forward {
    pub const URDF_X: Forward = Forward {
        yaw: 0.0,
        from: ForwardFrom::Urdf,
    };

    /// "+x", "+y", "-x", "-y", or the angle in degrees.
    pub fn describe(&self) -> String {
        let name = axis_name(self.yaw).map_or(
            format!("{:.1}° from +x", self.yaw.to_degrees()),
            String::from,
        );
        let from = match self.from {
            ForwardFrom::Urdf => "the URDF's",
            ForwardFrom::RobotFile => "set in the robot file",
            ForwardFrom::Legs => "chosen: the legs do not split three a side about x",
            ForwardFrom::LegNames => {
                "chosen: the legs do not split three a side about x, and their names say where the front is"
            }
        };
        if self.from != ForwardFrom::Legs {
            return format!("{name} ({from})");
        }
        // the legs split as well about the reverse: which end is the front, only the user knows
        // (the Cornell hexapod's README says -y where +y was chosen); named as a robot file
        // writes it, an axis or the angle in degrees
        let reverse = if self.yaw > 0.0 {
            self.yaw - std::f64::consts::PI
        } else {
            self.yaw + std::f64::consts::PI
        };
        let reverse =
            axis_name(reverse).map_or(format!("{:.1}", reverse.to_degrees()), String::from);
        format!(
            "{name} ({from}; {reverse} splits them as well: a robot file's `forward = \"{reverse}\"` walks that way)"
        )
    }
}

/// The axis a walking direction of `yaw` (rad about z) points along, if it points along one.
fn axis_name(yaw: f64) -> Option<&'static str> {
    let deg = yaw.to_degrees();
    [
        (0.0, "+x"),
        (90.0, "+y"),
        (180.0, "-x"),
        (-180.0, "-x"),
        (-90.0, "-y"),
    ]
    .iter()
    .find(|(a, _)| (deg - a).abs() < 1e-9)
    .map(|&(_, n)| n)
}
