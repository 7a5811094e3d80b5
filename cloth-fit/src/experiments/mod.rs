//! The paper's experiments as scenes (spec §6): each module has a serde `Params` (the RON
//! `params` block of `scenes/cloth-fit/<scene>.ron`) and `run(&Params, Size, &mut dyn
//! Recorder) -> Result<Report>`. Scene names map to modules: `static` → [`static_test`],
//! `static-consistency` → [`static_consistency`], `waving` → [`waving`], `errormap` →
//! [`errormap`], `confusion` → [`confusion`], `validate` → [`validate`], `pareto` →
//! [`pareto`], `real-roundtrip` → [`real_roundtrip`], `waving-linen` → [`waving_linen`].
//! C9 `skirt` needs the contact suite of `shells` and is not built.

pub mod common;
pub mod confusion;
pub mod errormap;
pub mod pareto;
pub mod real_roundtrip;
pub mod static_consistency;
pub mod static_test;
pub mod validate;
pub mod waving;
pub mod waving_linen;
