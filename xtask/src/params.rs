//! `cargo xtask params <method>`: an annotated template of a method's parameters.
//!
//! Nothing is written twice: the values come from a built-in scene file of the method (the
//! maintained, validated example), and each field's meaning and units from the doc comment on
//! the field in the crate's source (collected at build time by `build.rs`). Fields the scene does
//! not write but that have a serde default are listed after the block, with their doc.
//!
//! How a field finds its doc: the method's parameter struct is the struct of its crate whose
//! fields include every field the scene writes (the smallest such); a nested value's type is
//! read from its parent field's type (`shell: ShellScene`, `Option<Wind>`, `Vec<(String,
//! MeshSource)>`) or from the variant written before its `(` (`Grid(n: 12)`).

use std::collections::BTreeMap;

use crate::error::{io_err, Error, Result};
use crate::registry;
use crate::ronpath::{self, Entry, Kind, Seg};

include!(concat!(env!("OUT_DIR"), "/field_docs.rs"));

/// One documented field.
#[derive(Clone, Debug)]
struct Doc {
    owner: &'static str,
    name: &'static str,
    ty: &'static str,
    doc: &'static str,
    default: bool,
}

fn docs_of(krate: &str) -> Vec<Doc> {
    FIELD_DOCS
        .iter()
        .filter(|d| d.0 == krate)
        .map(|d| Doc { owner: d.1, name: d.2, ty: d.3, doc: d.4, default: d.5 })
        .collect()
}

/// Whether `name` is a field of any parameter struct of `krate` (from the doc comments collected
/// at build time); `None` when no field of that crate was collected (old-style runners), so the
/// question cannot be answered. Used to catch a misspelt field in a sweep before any task runs.
pub fn is_field_of_crate(krate: &str, name: &str) -> Option<bool> {
    let docs = docs_of(krate);
    (!docs.is_empty()).then(|| docs.iter().any(|d| d.name == name))
}

/// Type names mentioned in a type text that are owners in `docs` (`Option<Wind>` → `Wind`).
fn types_in(ty: &str, docs: &[Doc]) -> Vec<&'static str> {
    let mut v: Vec<&'static str> = Vec::new();
    for word in ty.split(|c: char| !(c.is_alphanumeric() || c == '_')) {
        if let Some(d) = docs.iter().find(|d| d.owner == word) {
            if !v.contains(&d.owner) {
                v.push(d.owner);
            }
        }
    }
    v
}

/// The struct holding every one of `fields` with the fewest fields.
fn root_type(docs: &[Doc], fields: &[String]) -> Option<&'static str> {
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for d in docs.iter().filter(|d| d.ty != "variant") {
        *count.entry(d.owner).or_default() += 1;
    }
    count
        .iter()
        .filter(|(o, _)| fields.iter().all(|f| docs.iter().any(|d| d.owner == **o && d.name == f)))
        .min_by_key(|(_, n)| **n)
        .map(|(o, _)| *o)
        .and_then(|o| docs.iter().find(|d| d.owner == o).map(|d| d.owner))
}

/// For each entry under `params`, the candidate owner types of its fields.
fn annotate<'a>(entries: &'a [Entry], docs: &[Doc]) -> Vec<(&'a Entry, Option<Doc>)> {
    let params: Vec<&Entry> = entries
        .iter()
        .filter(|e| matches!(e.path.first(), Some(Seg::Field(f)) if f == "params") && e.path.len() > 1)
        .collect();
    let top: Vec<String> = params
        .iter()
        .filter(|e| e.path.len() == 2)
        .filter_map(|e| match &e.path[1] {
            Seg::Field(f) => Some(f.clone()),
            Seg::Index(_) => None,
        })
        .collect();
    let root = root_type(docs, &top);
    // owners[path] = the types whose fields the value at `path` holds.
    let mut owners: BTreeMap<Vec<Seg>, Vec<&'static str>> = BTreeMap::new();
    owners.insert(vec![Seg::Field("params".into())], root.into_iter().collect());
    let mut out = Vec::new();
    for e in params {
        let parent = &e.path[..e.path.len() - 1];
        let mut cands = owners.get(parent).cloned().unwrap_or_default();
        let doc = match e.path.last() {
            Some(Seg::Field(f)) => {
                cands.iter().find_map(|o| docs.iter().find(|d| d.owner == *o && d.name == f)).cloned()
            }
            _ => None,
        };
        // What the value holds: types named by the field's type, or (for elements) the parent's.
        let mut mine: Vec<&'static str> = match &doc {
            Some(d) => types_in(d.ty, docs),
            None if matches!(e.path.last(), Some(Seg::Index(_))) => std::mem::take(&mut cands),
            None => Vec::new(),
        };
        if let Some(variant) = &e.name {
            let via: Vec<&'static str> = docs
                .iter()
                .filter(|d| d.ty != "variant" && d.owner.ends_with(&format!("::{variant}")))
                .map(|d| d.owner)
                .collect();
            for v in via {
                if !mine.contains(&v) {
                    mine.insert(0, v);
                }
            }
        }
        owners.insert(e.path.clone(), mine);
        out.push((e, doc));
    }
    out
}

/// Prints the template of `method` (`<crate>/<runner>`), or the methods of a crate, or every
/// method when `None`.
pub fn print(method: Option<&str>) -> Result<()> {
    let scenes = registry::builtin_scenes()?;
    let mut methods: Vec<&'static str> = registry::runners().iter().map(|r| r.method).collect();
    methods.sort_unstable();
    let want = method.unwrap_or("");
    let matching: Vec<&str> = methods.iter().copied().filter(|m| *m == want).collect();
    if matching.is_empty() {
        let listed: Vec<&str> =
            methods.iter().copied().filter(|m| want.is_empty() || m.split('/').next() == Some(want)).collect();
        if listed.is_empty() {
            return Err(Error::Usage(format!(
                "no method '{want}'; `cargo xtask params` lists them ({} in all)",
                methods.len()
            )));
        }
        say!("methods (cargo xtask params <method>):");
        for m in listed {
            let used: Vec<&str> = scenes.iter().filter(|s| s.method == m).map(|s| s.id.as_str()).collect();
            say!("  {m:32} {}", used.join(", "));
        }
        return Ok(());
    }
    let m = matching[0];
    let used: Vec<_> = scenes.iter().filter(|s| s.method == m).collect();
    let Some(example) = used.first() else {
        return Err(Error::Usage(format!("no built-in scene uses '{m}', so there is no template to print")));
    };
    let text = std::fs::read_to_string(&example.file).map_err(io_err(&example.file))?;
    let entries = ronpath::outline(&text);
    let krate = m.split('/').next().unwrap_or("");
    let docs = docs_of(krate);
    let notes = annotate(&entries, &docs);
    let params = ronpath::find(&entries, &[Seg::Field("params".into())])
        .ok_or_else(|| Error::Usage(format!("{}: no params block", example.file.display())))?;
    say!("// Parameters of {m}: the values of {} ({}),", example.id, example.file.display());
    if used.len() > 1 {
        say!("// also used by {}.", used[1..].iter().map(|s| s.id.as_str()).collect::<Vec<_>>().join(", "));
    }
    say!("// A value written (quick, default, full) is picked by the run mode (--quick, default, --full).");
    say!("// Override any field with --set path=VALUE, e.g. --set {}", example_path(&notes));
    // The params block, line by line, each field preceded by its doc.
    let start = text[..params.value.start].rfind('\n').map(|i| i + 1).unwrap_or(0);
    let block = &text[start..params.value.end];
    let mut offset = start;
    say!("(");
    for line in block.split_inclusive('\n') {
        let (lo, hi) = (offset, offset + line.len());
        offset = hi;
        let indent: String = line.chars().take_while(|c| c.is_whitespace() && *c != '\n').collect();
        for (e, d) in notes
            .iter()
            .filter(|(e, _)| e.key_at >= lo && e.key_at < hi && matches!(e.path.last(), Some(Seg::Field(_))))
        {
            if let Some(d) = d {
                let what = if d.doc.is_empty() { format!("({})", d.ty) } else { format!("{} ({})", d.doc, d.ty) };
                let opt = if d.default { " Optional." } else { "" };
                say!("{indent}// {}: {what}{opt}", scene_path(&e.path));
            }
        }
        let shown = if lo == start { line.trim_start() } else { line };
        say!("{}", shown.trim_end_matches('\n'));
    }
    say!(")");
    // Optional fields the example does not write.
    let mut missing = Vec::new();
    for (e, _) in notes.iter().filter(|(e, _)| matches!(e.kind, Kind::Paren { .. })) {
        let written: Vec<String> = entries
            .iter()
            .filter(|c| c.path.len() == e.path.len() + 1 && c.path.starts_with(&e.path))
            .filter_map(|c| match c.path.last() {
                Some(Seg::Field(f)) => Some(f.clone()),
                _ => None,
            })
            .collect();
        if written.is_empty() {
            continue;
        }
        let Some(owner) = root_or_owner(&notes, e, &docs, &written) else { continue };
        for d in docs
            .iter()
            .filter(|d| d.owner == owner && d.default && d.ty != "variant" && !written.contains(&d.name.to_string()))
        {
            missing.push(format!("{}.{}: {} ({})", scene_path(&e.path), d.name, d.doc, d.ty));
        }
    }
    let top: Vec<String> = entries
        .iter()
        .filter(|c| c.path.len() == 2 && matches!(&c.path[0], Seg::Field(f) if f == "params"))
        .filter_map(|c| match &c.path[1] {
            Seg::Field(f) => Some(f.clone()),
            _ => None,
        })
        .collect();
    if let Some(root) = root_type(&docs, &top) {
        for d in docs.iter().filter(|d| d.owner == root && d.default && !top.contains(&d.name.to_string())) {
            missing.insert(0, format!("{}: {} ({})", d.name, d.doc, d.ty));
        }
    }
    if !missing.is_empty() {
        say!("// Optional fields not written above (their defaults apply):");
        for m in missing {
            say!("//   {m}");
        }
    }
    Ok(())
}

fn root_or_owner(notes: &[(&Entry, Option<Doc>)], e: &Entry, docs: &[Doc], written: &[String]) -> Option<&'static str> {
    // The owner whose fields include everything written in this block.
    let mut cands: Vec<&'static str> = notes
        .iter()
        .find(|(x, _)| x.path == e.path)
        .and_then(|(_, d)| d.as_ref().map(|d| types_in(d.ty, docs)))
        .unwrap_or_default();
    if let Some(v) = &e.name {
        cands.extend(docs.iter().filter(|d| d.owner.ends_with(&format!("::{v}"))).map(|d| d.owner));
    }
    cands.into_iter().find(|o| written.iter().all(|w| docs.iter().any(|d| d.owner == *o && d.name == w)))
}

fn scene_path(p: &[Seg]) -> String {
    crate::scene::display_path(p)
}

fn example_path(notes: &[(&Entry, Option<Doc>)]) -> String {
    notes
        .iter()
        .filter(|(e, _)| matches!(e.kind, Kind::Atom) && matches!(e.path.last(), Some(Seg::Field(_))))
        .max_by_key(|(e, _)| e.path.len())
        .map(|(e, _)| format!("{}=VALUE", scene_path(&e.path)))
        .unwrap_or_else(|| "field=VALUE".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_docs_were_collected_from_the_sources() {
        // The render scene's parameter struct lives in xtask's geom-core runners.
        let docs = docs_of("geom-core");
        let fov = docs.iter().find(|d| d.name == "fov_y_deg").expect("fov_y_deg documented");
        assert!(fov.doc.contains("degrees"), "{}", fov.doc);
        let text = std::fs::read_to_string(crate::paths::scenes_dir().unwrap().join("geom-core/render.ron")).unwrap();
        let entries = ronpath::outline(&text);
        let notes = annotate(&entries, &docs);
        let size = notes
            .iter()
            .find(|(e, _)| scene_path(&e.path) == "size")
            .and_then(|(_, d)| d.clone())
            .expect("size documented");
        assert!(size.doc.contains("pixels"), "{}", size.doc);
        // A field of an enum variant: Icosphere(radius: …).
        let radius = notes.iter().find(|(e, _)| scene_path(&e.path).ends_with("radius")).and_then(|(_, d)| d.clone());
        assert!(radius.is_some(), "variant field documented");
    }
}
