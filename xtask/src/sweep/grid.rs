//! The full grid over a sweep's varied parameters.

/// Every combination of `dims` (one list of values per varied parameter), in the order of nested
/// loops with the first parameter outermost: `[[a, b], [1, 2]]` → `a 1, a 2, b 1, b 2`. No
/// dimension gives one empty combination; an empty dimension gives none.
pub fn expand(dims: &[Vec<String>]) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = vec![Vec::new()];
    for values in dims {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                values.iter().map(move |v| {
                    let mut p = prefix.clone();
                    p.push(v.clone());
                    p
                })
            })
            .collect();
    }
    out
}

/// The id of task `i` of `n`: its index, zero-padded to at least four digits (`0007`), so that
/// ids sort like the tasks.
pub fn task_id(i: usize, n: usize) -> String {
    let width = n.saturating_sub(1).to_string().len().max(4);
    format!("{i:0width$}")
}
