//! What the twin simulates of the robot, one model per device: the drive motors and encoders
//! ([`motor`]), the batteries ([`battery`]), the two microcontrollers' ported firmware and their
//! serial timing ([`firmware`]), the SICK laser and its optics ([`laser`]), the sonar ring
//! ([`sonar`]) and the pan-tilt head that carries the laser ([`pan_tilt`]).

pub mod battery;
pub mod firmware;
pub mod laser;
pub mod motor;
pub mod pan_tilt;
pub mod sonar;
