//! The experiments of `shells` (STYLE.md): each module holds one scene's parameters (`Params`,
//! the RON `params` block), its `run(&Params, Size, &mut dyn Recorder) -> Result<Report>` and the
//! figures it reports; `protocol` is the run loop they share, `accuracy` the building blocks of
//! the accuracy-versus-time benchmark.
//!
//! | scene (`scenes/shells/…`) | module |
//! |---|---|
//! | `calib-bend` | [`calib_bend`] |
//! | `cantilever` | [`cantilever`] |
//! | `drape` | [`drape`] |
//! | `fold-stress` | [`fold_stress`] |
//! | `plastic-crease` | [`plastic_crease`] |
//! | `wind-flag` | [`wind_flag`] |
//! | `sphere-drop`, `spinning-sphere`, `table`, `twist` | [`contact`] |

pub mod accuracy;
pub mod calib_bend;
pub mod cantilever;
pub mod contact;
pub mod drape;
pub mod fold_stress;
pub mod plastic_crease;
pub mod protocol;
pub mod wind_flag;

/// The `params` block of a scene file (`scenes/shells/<scene>.ron`, whose top level is
/// `(method: …, description: …, params: (…))`) as an experiment's `Params`; an unreadable file
/// or a bad field is an error naming the file and the parser's line and column. Optional fields
/// are written without `Some(…)` (RON's `implicit_some`, as `cargo xtask` reads scene files).
///
/// ```no_run
/// use geom_core::experiment::Size;
/// use geom_core::record::NullRecorder;
/// use shells::experiments::{contact, scene_params};
/// let p: contact::Params = scene_params(std::path::Path::new("scenes/shells/table.ron")).unwrap();
/// let r = contact::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap();
/// assert!(r.all_pass());
/// ```
pub fn scene_params<P: serde::de::DeserializeOwned>(path: &std::path::Path) -> crate::Result<P> {
    #[derive(serde::Deserialize)]
    struct File<P> {
        #[allow(dead_code)]
        method: String,
        #[allow(dead_code)]
        #[serde(default)]
        description: String,
        params: P,
    }
    let name = path.display();
    let text = std::fs::read_to_string(path)
        .map_err(|e| crate::Error::BadParameter(format!("{name}: cannot read the scene file: {e}")))?;
    // Scene files write optional fields without `Some(…)`, as xtask reads them.
    let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let f: File<P> = opts.from_str(&text).map_err(|e| crate::Error::BadParameter(format!("{name}: {e}")))?;
    Ok(f.params)
}
