//! Set-up: the physics decisions a scenario leaves to hexsim, made once from the loaded robot,
//! gait and contact — the ground fitted to the robot's weight ([`ground`]), the servo gains
//! ([`servo`]), and the time step the contact, the landing feet and the servos allow
//! ([`time_step`]). Each is a function of physical quantities, tested here; `scenario` reads and
//! checks the file's fields and calls them, and `hexsim robot` shows what they make of a robot.

pub mod ground;
pub mod servo;
pub mod time_step;
