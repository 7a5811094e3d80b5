//! The partner-dance half of the paper (spec §3.13): [`grammar`] (stances, transitions,
//! patterns, the seven basic patterns and the composable ones). The duet generator is
//! [`crate::data::duet`], the dance metrics [`crate::eval::dance`].

pub mod grammar;

pub use grammar::{basic_patterns, composable, label_set, DanceLabel, Half, Pattern, Stance, Transition};
