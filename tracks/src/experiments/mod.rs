//! The experiments of `tracks` (the paper's figures and table, Bergou et al. 2007 §5): each
//! module holds one scene family's parameters (the RON `params` block, `deny_unknown_fields`)
//! and its `run(&Params, Size, &mut dyn Recorder) -> Result<Report>`. [`protocol`] is the
//! lockstep tracked/untracked run they share, [`anchors`] the averaged-versus-pointwise run of
//! Fig. 3 and 4, [`variants`] the material-variant machinery of Fig. 8 and 9.

pub mod anchors;
pub mod bag;
pub mod bag_variants;
pub mod box_twist;
pub mod box_variants;
pub mod claims;
pub mod fig3_band;
pub mod fig4_sphere;
pub mod fig5_heterogeneous;
pub mod fig6_partitions;
pub mod fig7_clustering;
pub mod flag;
pub mod protocol;
pub mod table55;
pub mod track;
pub mod variants;
pub mod xavier;
