//! Rigging a user's character mesh ([`rig_character`], the library call behind `cargo xtask
//! rig`): any scale, any of the 24 axis-aligned orientations (found from the shape or given),
//! a bounded discrete search, non-manifold vertices split, unrepairable defects refused with an
//! error naming them.
//!
//! The mesh is turned into the template's frame (+Y up, facing +Z) by the exact signed
//! permutation of its [`Orientation`], rigged there by [`crate::autorig`] (which normalises the
//! scale), and the joints are turned back: a Z-up, a −Z-facing and a +X-facing copy of one mesh
//! give the same rig.
//!
//! ```no_run
//! use rigging::character::{rig_character, CharacterOptions};
//! use rigging::SkeletonTemplate;
//! let (m, _) = geom_core::io::read_any("hero.obj").unwrap().triangulate_fan().unwrap();
//! let r = rig_character(&m.positions, &m.faces, &SkeletonTemplate::human(), &CharacterOptions::default()).unwrap();
//! println!("{} ({}): {} joints", r.orientation, if r.rig.discrete.certified_optimal { "optimal" } else { "budget" }, r.joints.len());
//! ```

use geom_core::math::Pt3;

use crate::embed::SearchBudget;
use crate::error::{Result, RigError};
use crate::orient::{detect_orientation, Axis, Orientation, OrientationReport};
use crate::rig::{autorig, prepare_embedding, Rig};
use crate::template::SkeletonTemplate;
use crate::{Hint, RigOptions};

/// Options of [`rig_character`].
#[derive(Clone, Debug, PartialEq)]
pub struct CharacterOptions {
    /// The rigging options (τ, search budget, …).
    pub rig: RigOptions,
    /// The input axis that is up; `None` = detect.
    pub up: Option<Axis>,
    /// The input axis the character faces; `None` = detect.
    pub front: Option<Axis>,
    /// τ (normalized units) of the distance field used to detect the orientation (coarser than
    /// the rig's: a quarter of the cost at twice τ); the rig's τ is used if nothing embeds there.
    pub detect_tau: f64,
    /// Expansions per orientation while detecting.
    pub detect_expansions: usize,
}

impl Default for CharacterOptions {
    fn default() -> Self {
        Self { rig: RigOptions::default(), up: None, front: None, detect_tau: 0.006, detect_expansions: 2000 }
    }
}

/// A rigged character.
#[derive(Clone, Debug)]
pub struct CharacterRig {
    /// The rig in the template's frame (+Y up, facing +Z; the input's units): its mesh is the
    /// prepared input mesh turned by `orientation`.
    pub rig: Rig,
    /// The orientation of the input.
    pub orientation: Orientation,
    /// How it was found (`None` when both axes were given).
    pub detection: Option<OrientationReport>,
    /// Embedded joints (template order) in the input mesh's own axes and units.
    pub joints: Vec<Pt3>,
}

impl CharacterRig {
    /// A point of the rig's frame in the input's axes.
    pub fn to_input(&self, p: &Pt3) -> Pt3 {
        self.orientation.point_from_canonical(p)
    }
}

/// Rigs a character mesh given as a raw triangle soup in any axes and units (see the module
/// docs). Hints are in the input's coordinates. Errors: the defects [`crate::prep::prepare`]
/// cannot repair (holes, non-manifold edges, several components, no volume), up and front on the
/// same axis, no embedding in any allowed orientation.
pub fn rig_character(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    sk: &SkeletonTemplate,
    o: &CharacterOptions,
) -> Result<CharacterRig> {
    rig_character_with_hints(positions, faces, sk, &[], o)
}

/// [`rig_character`] with hints (input coordinates).
pub fn rig_character_with_hints(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    sk: &SkeletonTemplate,
    hints: &[Hint],
    o: &CharacterOptions,
) -> Result<CharacterRig> {
    o.rig.validate()?;
    if let (Some(u), Some(f)) = (o.up, o.front) {
        Orientation::new(u, f)?;
    }
    let allowed: Vec<Orientation> = Orientation::all()
        .into_iter()
        .filter(|c| o.up.is_none_or(|u| c.up == u) && o.front.is_none_or(|f| c.front == f))
        .collect();
    let (orientation, detection) = if allowed.len() == 1 {
        (allowed[0], None)
    } else {
        let rep = detect(positions, faces, sk, o, &allowed)?;
        (rep.orientation, Some(rep))
    };
    let turned: Vec<Pt3> = positions.iter().map(|p| orientation.point_to_canonical(p)).collect();
    let hints: Vec<Hint> = hints
        .iter()
        .map(|h| match h {
            Hint::Near { joint, point, radius } => {
                let p = orientation.point_to_canonical(&Pt3::from(*point));
                Hint::Near { joint: joint.clone(), point: [p.x, p.y, p.z], radius: *radius }
            }
            other => other.clone(),
        })
        .collect();
    let rig = autorig(&turned, faces, sk, &hints, &o.rig)?;
    let joints = rig.joints.iter().map(|p| orientation.point_from_canonical(p)).collect();
    Ok(CharacterRig { rig, orientation, detection, joints })
}

/// Orientation detection on a coarse distance field, then at the rig's τ if nothing embeds.
fn detect(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    sk: &SkeletonTemplate,
    o: &CharacterOptions,
    allowed: &[Orientation],
) -> Result<OrientationReport> {
    let budget =
        SearchBudget { max_expansions: o.detect_expansions, max_seconds: None, completion_visits: o.detect_expansions };
    let mut last = None;
    let taus = if o.detect_tau > o.rig.tau { vec![o.detect_tau, o.rig.tau] } else { vec![o.rig.tau] };
    for tau in taus {
        let ro = RigOptions { tau, ..o.rig.clone() };
        let (_, e) = prepare_embedding(positions, faces, sk, &[], &ro)?;
        match detect_orientation(&e.graph, sk, &ro, &budget, allowed) {
            Ok(r) => return Ok(r),
            Err(err @ RigError::NoEmbedding { .. }) => last = Some(err),
            Err(err) => return Err(err),
        }
    }
    Err(last.unwrap_or(RigError::NoEmbedding { best_partial: None, expanded: 0 }))
}
