//! Where things are, found at run time (issue 23, item 1): the built-in `scenes/` and `assets/`
//! folders, the default `out/` folder, and how a path given by a user resolves.
//!
//! - A path on the command line resolves against the current directory (the operating system
//!   does that).
//! - A path inside a scene file resolves against that file's folder ([`resolve_in`], exposed to
//!   runners as [`crate::registry::RunCtx::resolve`]).
//! - The built-in data (the folder holding `scenes/` and `assets/`) is looked for, in order: the
//!   `--scenes DIR` option (its parent holds `assets/`), the nearest ancestor of the running
//!   binary's folder that holds both, then the nearest ancestor of the current directory that
//!   holds both. Nothing depends on the folder the binary was compiled in, so a copied or
//!   installed binary works (install the data beside it, e.g. `bin/xtask` with `scenes/` and
//!   `assets/` next to `bin/`).
//! - The default output root is `out/` in the checkout the current directory is in (the nearest
//!   ancestor holding `scenes/` and `assets/`), or `./out` anywhere else.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::error::{Error, Result};

thread_local! {
    /// The folder of the scene file whose runner is running on this thread.
    static SCENE_BASE: RefCell<Option<PathBuf>> = const { RefCell::new(None) };
}

/// Runs `f` (a scene's runner) with `file`'s folder as the base that [`relative_base`] returns
/// on this thread, so that runners written before [`crate::registry::RunCtx::resolve`] existed
/// (they join their paths to `out::workspace_root()`) also resolve a scene's paths against the
/// scene file's folder.
pub fn with_scene_base<R>(file: &Path, f: impl FnOnce() -> R) -> R {
    let dir = absolute(file).parent().map(Path::to_path_buf);
    let prev = SCENE_BASE.with(|b| b.replace(dir));
    let r = f();
    SCENE_BASE.with(|b| *b.borrow_mut() = prev);
    r
}

/// What a relative path in a scene resolves against: the running scene file's folder (inside
/// [`with_scene_base`]), else the data root.
pub fn relative_base() -> PathBuf {
    SCENE_BASE.with(|b| b.borrow().clone()).unwrap_or_else(data_root)
}

static SCENES_OVERRIDE: OnceLock<PathBuf> = OnceLock::new();

/// Sets the `--scenes DIR` override (once per process; later calls are ignored). A relative
/// `dir` is taken against the current directory.
pub fn set_scenes_override(dir: &Path) {
    let abs = absolute(dir);
    let _ = SCENES_OVERRIDE.set(abs);
}

/// `p` made absolute against the current directory (not canonicalised: symlinks are kept).
pub fn absolute(p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().map(|c| c.join(p)).unwrap_or_else(|_| p.to_path_buf())
    }
}

/// Resolves a path written inside a file against that file's folder: absolute paths stay as they
/// are, relative ones are joined to `file`'s parent folder.
pub fn resolve_in(file: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        return p.to_path_buf();
    }
    match file.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(p),
        _ => p.to_path_buf(),
    }
}

fn is_data_root(dir: &Path) -> bool {
    dir.join("scenes").is_dir() && dir.join("assets").is_dir()
}

fn nearest_data_root(start: &Path) -> Option<PathBuf> {
    start.ancestors().find(|d| is_data_root(d)).map(Path::to_path_buf)
}

/// The folder holding the built-in `scenes/` and `assets/`, found at run time (see the module
/// documentation), or `None` when none is found.
pub fn find_data_root() -> Option<PathBuf> {
    if let Some(s) = SCENES_OVERRIDE.get() {
        return Some(s.parent().map(Path::to_path_buf).unwrap_or_else(|| s.clone()));
    }
    let exe_dir = std::env::current_exe().ok().and_then(|e| e.parent().map(Path::to_path_buf));
    if let Some(root) = exe_dir.as_deref().and_then(nearest_data_root) {
        return Some(root);
    }
    std::env::current_dir().ok().as_deref().and_then(nearest_data_root)
}

/// The data root, or the current directory when none is found (so that messages name the path
/// that was tried).
pub fn data_root() -> PathBuf {
    find_data_root().unwrap_or_else(|| absolute(Path::new(".")))
}

/// The built-in scene folder: `--scenes DIR`, else `<data root>/scenes`; an error saying where it
/// was looked for when there is none.
pub fn scenes_dir() -> Result<PathBuf> {
    if let Some(s) = SCENES_OVERRIDE.get() {
        return if s.is_dir() {
            Ok(s.clone())
        } else {
            Err(Error::Usage(format!("--scenes {}: no such folder", s.display())))
        };
    }
    find_data_root().map(|r| r.join("scenes")).ok_or_else(|| {
        let exe = std::env::current_exe().map(|e| e.display().to_string()).unwrap_or_else(|_| "?".into());
        Error::Usage(format!(
            "the built-in scenes were not found: no folder holding scenes/ and assets/ above the binary \
             ({exe}) or the current directory; pass --scenes DIR"
        ))
    })
}

/// The default output root: `<checkout>/out` when the current directory is inside a checkout (a
/// folder holding `scenes/` and `assets/`), else `./out`.
pub fn default_out_root() -> PathBuf {
    let cwd = absolute(Path::new("."));
    nearest_data_root(&cwd).unwrap_or(cwd).join("out")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_paths_resolve_against_the_scene_folder() {
        let f = Path::new("/home/u/shots/my.ron");
        assert_eq!(resolve_in(f, Path::new("mygrid.obj")), Path::new("/home/u/shots/mygrid.obj"));
        assert_eq!(resolve_in(f, Path::new("../meshes/a.obj")), Path::new("/home/u/shots/../meshes/a.obj"));
        assert_eq!(resolve_in(f, Path::new("/abs/b.obj")), Path::new("/abs/b.obj"));
        assert_eq!(resolve_in(Path::new("my.ron"), Path::new("a.obj")), Path::new("a.obj"));
        assert_eq!(resolve_in(Path::new("sub/my.ron"), Path::new("a.obj")), Path::new("sub/a.obj"));
    }

    #[test]
    fn runners_resolve_against_the_scene_folder_while_they_run() {
        let inside = with_scene_base(Path::new("/home/u/shots/my.ron"), relative_base);
        assert_eq!(inside, Path::new("/home/u/shots"));
        assert_ne!(relative_base(), Path::new("/home/u/shots"), "restored after the run");
    }

    #[test]
    fn data_root_is_found_from_a_folder_inside_it() {
        let tmp = std::env::temp_dir().join(format!("xtask-paths-{}", std::process::id()));
        let deep = tmp.join("a/b/c");
        std::fs::create_dir_all(&deep).unwrap();
        assert_eq!(nearest_data_root(&deep), None);
        std::fs::create_dir_all(tmp.join("a/scenes")).unwrap();
        std::fs::create_dir_all(tmp.join("a/assets")).unwrap();
        assert_eq!(nearest_data_root(&deep), Some(tmp.join("a")));
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    #[test]
    fn this_checkout_is_a_data_root() {
        // The test binary runs inside the checkout (cargo sets the current directory to the
        // crate), so the run-time search finds the same scenes as the workspace holds.
        let root = find_data_root().expect("checkout found at run time");
        assert!(root.join("scenes/geom-core/render.ron").is_file(), "{}", root.display());
    }
}
