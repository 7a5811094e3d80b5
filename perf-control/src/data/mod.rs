//! Procedural example data (spec §3.13): walks from geom-core's synthesiser with an exact
//! segmentation at foot plants, mouse-like paths, and the Lindy-like duet ([`duet`]).

pub mod capture;
pub mod duet;
pub mod mouse;
pub mod walk;

pub use mouse::{mouse_path, straight_stroke};
pub use walk::{take_from_walk, walk_motion, walk_motion_with_turns, walk_take, SharpTurn};
