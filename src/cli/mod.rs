//! One module per subcommand. Each parses its flags (with units in their names) and calls the
//! library; no physics lives here.

pub mod calibrate;
pub mod contact;
pub mod contact_normal;
pub mod contact_tangential;
pub mod diagnose;
pub mod elements;
pub mod film;
pub mod surface;
