//! Cross-crate integration tests and the hard-case stress suite live in `tests/tests/`; this
//! library only holds helpers they share.

use geom_core::experiment::{Report, Value};
use serde::de::DeserializeOwned;

/// Runs `f` inside a rayon pool of `threads` threads.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool of 1 or 2 threads can always be built")
        .install(f)
}

/// The reproducible figures of a report as text (exact: `{:?}` of an `f64` round-trips), so
/// that two runs compare bit for bit and a difference prints readably.
pub fn figures_text(r: &Report) -> Vec<String> {
    r.reproducible_figures()
        .into_iter()
        .map(|(k, v)| match v {
            Value::Num(x) => format!("{k} = {x:?} ({:#018x})", x.to_bits()),
            other => format!("{k} = {other:?}"),
        })
        .collect()
}

/// Runs an experiment with 1 and with 2 rayon threads and asserts that every figure not marked
/// as timing is bitwise identical (the determinism ARCHITECTURE.md promises). Returns the
/// single-thread report for further checks.
pub fn assert_thread_independent(name: &str, run: impl Fn() -> Report + Sync) -> Report {
    let one = with_threads(1, &run);
    let two = with_threads(2, &run);
    let (a, b) = (figures_text(&one), figures_text(&two));
    assert!(!a.is_empty(), "{name}: the report has no reproducible figure");
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x, y, "{name}: figure differs between 1 and 2 threads");
    }
    assert_eq!(a.len(), b.len(), "{name}: different figure sets with 1 and 2 threads");
    one
}

/// Asserts that every check of the report passes, listing the failures.
pub fn assert_checks_pass(name: &str, r: &Report) {
    let failed: Vec<String> = r
        .failed_checks()
        .map(|c| format!("{} = {} (target {}; {})", c.key, c.value, c.target.describe(), c.source))
        .collect();
    assert!(failed.is_empty(), "{name}: failed checks:\n  {}", failed.join("\n  "));
}

/// The `params` block of the built-in scene `scenes/<id>.ron` (e.g. `"curve-skin/elbow-bend"`)
/// as the experiment's `Params`: the tests run exactly the scenes `cargo xtask` runs, at
/// `Size::Tiny`. Panics with the file and the parse error (line, column) when it does not parse.
pub fn scene_params<P: DeserializeOwned>(id: &str) -> P {
    #[derive(serde::Deserialize)]
    struct Envelope<P> {
        #[allow(dead_code)]
        method: String,
        #[allow(dead_code)]
        #[serde(default)]
        description: String,
        params: P,
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(format!("{id}.ron"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let env: Envelope<P> = opts.from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    env.params
}
