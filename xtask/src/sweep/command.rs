//! Task command lines: one complete shell command per task, with absolute paths, so that a node
//! sharing the file system runs it from any folder.

use std::path::Path;

/// `s` quoted for a POSIX shell: unchanged when it holds only characters no shell treats
/// specially, else in single quotes (a `'` inside becomes `'\''`).
pub fn shell_quote(s: &str) -> String {
    let plain = !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "_-+=./:,@%^".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// A command line from its words, each quoted.
pub fn join(words: &[String]) -> String {
    words.iter().map(|w| shell_quote(w)).collect::<Vec<_>>().join(" ")
}

/// Splits a command line of [`join`] back into words (single quotes, `'\''`, plain words).
/// Returns `None` for a line this module would not have written (other quoting). Used by the
/// tests to read command lines back.
#[cfg(test)]
pub fn split(line: &str) -> Option<Vec<String>> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut in_word = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                loop {
                    match chars.next()? {
                        '\'' => break,
                        x => cur.push(x),
                    }
                }
            }
            '\\' => {
                in_word = true;
                cur.push(chars.next()?);
            }
            ' ' | '\t' => {
                if in_word {
                    words.push(std::mem::take(&mut cur));
                    in_word = false;
                }
            }
            '"' | '$' | '`' | ';' | '&' | '|' | '<' | '>' => return None,
            x => {
                in_word = true;
                cur.push(x);
            }
        }
    }
    if in_word {
        words.push(cur);
    }
    Some(words)
}

/// The mode flag of a run (`--quick`, `--full`, none for the default).
pub fn mode_flag(mode: crate::scene::Mode) -> Option<&'static str> {
    match mode {
        crate::scene::Mode::Quick => Some("--quick"),
        crate::scene::Mode::Default => None,
        crate::scene::Mode::Full => Some("--full"),
    }
}

/// The binary and, when known, `--scenes DIR` (the built-in scenes this binary found when
/// planning), so that a task finds them whatever folder it starts in.
fn head(xtask: &Path, scenes: Option<&Path>) -> Vec<String> {
    let mut w = vec![xtask.display().to_string()];
    if let Some(s) = scenes {
        w.extend(["--scenes".into(), s.display().to_string()]);
    }
    w
}

/// The words of a scene task:
/// `XTASK [--scenes S] run SCENE [--quick|--full] --out DIR --resume --set P=V …`.
pub fn scene_task(
    xtask: &Path,
    scenes: Option<&Path>,
    scene: &Path,
    mode: crate::scene::Mode,
    dir: &Path,
    sets: &[(String, String)],
) -> Vec<String> {
    let mut w = head(xtask, scenes);
    w.extend(["run".into(), scene.display().to_string()]);
    w.extend(mode_flag(mode).map(str::to_string));
    w.extend(["--out".into(), dir.display().to_string(), "--resume".into()]);
    for (p, v) in sets {
        w.extend(["--set".into(), format!("{p}={v}")]);
    }
    w
}

/// The words of a bench point:
/// `XTASK [--scenes S] bench CRATE [--quick|--full] --sweep K --point I --out DIR --resume`.
pub fn bench_task(
    xtask: &Path,
    scenes: Option<&Path>,
    krate: &str,
    mode: crate::scene::Mode,
    sweep: &str,
    point: usize,
    dir: &Path,
) -> Vec<String> {
    let mut w = head(xtask, scenes);
    w.extend(["bench".into(), krate.to_string()]);
    w.extend(mode_flag(mode).map(str::to_string));
    w.extend([
        "--sweep".into(),
        sweep.to_string(),
        "--point".into(),
        point.to_string(),
        "--out".into(),
        dir.display().to_string(),
        "--resume".into(),
    ]);
    w
}
