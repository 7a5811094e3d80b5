//! The BVH grammar (motion-graph.md §2.2) parsed into raw joints (file units, Euler degrees) and
//! a flat value array. Iterative (no recursion), so deeply nested input cannot overflow the
//! stack; allocation follows the data actually present, never the declared frame count.

use super::lex::{Lexer, Tok};
use crate::anim::skeleton::Channel;
use crate::error::BvhError;

/// A joint as written in the file.
#[derive(Clone, Debug)]
pub(crate) struct RawJoint {
    pub name: String,
    pub parent: Option<usize>,
    pub offset: [f64; 3],
    pub channels: Vec<Channel>,
    pub end_site: bool,
}

/// How to treat a frame count that does not match the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mode {
    /// Exactly the declared frames: fewer is an error, extra rows are ignored (not parsed).
    Strict,
    /// All complete rows found; zero is an error.
    Lenient,
    /// All complete rows found; zero is fine (reporting only).
    Inspect,
}

/// Everything read from a BVH text.
#[derive(Clone, Debug)]
pub(crate) struct Parsed {
    pub joints: Vec<RawJoint>,
    pub channels: usize,
    pub declared: usize,
    pub frame_time: f64,
    /// Frames kept in `values`.
    pub frames: usize,
    /// `frames × channels` values, row-major.
    pub values: Vec<f64>,
    /// Complete rows of values present in the file.
    pub rows_present: usize,
    /// Values of an incomplete final row.
    pub trailing: usize,
}

fn parse_num(t: Tok) -> Result<f64, BvhError> {
    match t.text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(BvhError::BadNumber { line: t.line, text: t.text.to_string() }),
    }
}

fn misplaced(t: Tok, why: &str) -> BvhError {
    let keyword = if why.is_empty() { t.text.to_string() } else { format!("{} ({why})", t.text) };
    BvhError::UnknownKeyword { line: t.line, keyword }
}

/// Reads the next token inside the hierarchy, where end of file means an unclosed brace.
fn need<'a>(lex: &mut Lexer<'a>) -> Result<Tok<'a>, BvhError> {
    lex.next_tok().ok_or(BvhError::UnbalancedBraces { line: lex.last_line })
}

/// Expects `{` after a joint name or `End Site`.
fn open_brace(lex: &mut Lexer) -> Result<(), BvhError> {
    let t = need(lex)?;
    if t.text == "{" {
        Ok(())
    } else {
        Err(BvhError::UnbalancedBraces { line: t.line })
    }
}

/// `CHANNELS n name…` after the keyword.
fn parse_channels(lex: &mut Lexer, kw: Tok, joint: &str) -> Result<Vec<Channel>, BvhError> {
    let nt = need(lex)?;
    let n: usize = nt.text.parse().map_err(|_| BvhError::ChannelCount {
        line: nt.line,
        msg: format!("channel count '{}' is not a whole number", nt.text),
    })?;
    let mut chans: Vec<Channel> = Vec::with_capacity(n.min(6));
    for i in 0..n {
        let t = need(lex)?;
        let Some(c) = Channel::from_bvh_name(t.text) else {
            return Err(BvhError::ChannelCount {
                line: t.line,
                msg: format!(
                    "joint '{joint}' declares {n} channels but '{}' (number {}) is not a channel name",
                    t.text,
                    i + 1
                ),
            });
        };
        if chans.contains(&c) {
            if c.is_rotation() {
                return Err(BvhError::RepeatedAxis { line: t.line, joint: joint.to_string() });
            }
            return Err(BvhError::ChannelCount {
                line: t.line,
                msg: format!("joint '{joint}' repeats channel {}", c.bvh_name()),
            });
        }
        chans.push(c);
    }
    if let Some(t) = lex.peek() {
        if Channel::from_bvh_name(t.text).is_some() {
            return Err(BvhError::ChannelCount {
                line: t.line,
                msg: format!("joint '{joint}' declares {n} channels (line {}) but lists more", kw.line),
            });
        }
    }
    Ok(chans)
}

/// A joint being read: index into the output and whether its OFFSET/CHANNELS were seen.
struct Open {
    idx: usize,
    has_offset: bool,
    has_channels: bool,
}

/// Parses `HIERARCHY … }` (everything up to, not including, `MOTION`).
fn parse_hierarchy(lex: &mut Lexer) -> Result<Vec<RawJoint>, BvhError> {
    let t = lex
        .next_tok()
        .ok_or(BvhError::UnknownKeyword { line: lex.last_line, keyword: "end of file (expected HIERARCHY)".into() })?;
    if t.text != "HIERARCHY" {
        return Err(misplaced(t, "expected HIERARCHY"));
    }
    let t = lex
        .next_tok()
        .ok_or(BvhError::UnknownKeyword { line: lex.last_line, keyword: "end of file (expected ROOT)".into() })?;
    if t.text != "ROOT" {
        return Err(misplaced(t, "expected ROOT"));
    }
    let name = need(lex)?;
    if name.text == "{" {
        return Err(misplaced(name, "expected a joint name"));
    }
    open_brace(lex)?;
    let mut joints = vec![RawJoint {
        name: name.text.to_string(),
        parent: None,
        offset: [0.0; 3],
        channels: vec![],
        end_site: false,
    }];
    let mut names = std::collections::HashSet::new();
    names.insert(name.text.to_string());
    let mut stack = vec![Open { idx: 0, has_offset: false, has_channels: false }];
    while let Some(top) = stack.last_mut() {
        let t = need(lex)?;
        let cur = top.idx;
        match t.text {
            "OFFSET" => {
                if top.has_offset {
                    return Err(misplaced(t, "repeated"));
                }
                let mut o = [0.0; 3];
                for v in &mut o {
                    *v = parse_num(need(lex)?)?;
                }
                joints[cur].offset = o;
                top.has_offset = true;
            }
            "CHANNELS" => {
                if joints[cur].end_site {
                    return Err(misplaced(t, "End Site has no channels"));
                }
                if top.has_channels {
                    return Err(misplaced(t, "repeated"));
                }
                let name = joints[cur].name.clone();
                joints[cur].channels = parse_channels(lex, t, &name)?;
                top.has_channels = true;
            }
            "JOINT" | "End" => {
                if joints[cur].end_site {
                    return Err(misplaced(t, "End Site cannot have children"));
                }
                if !top.has_offset {
                    return Err(misplaced(t, "expected OFFSET first"));
                }
                if joints.len() >= u16::MAX as usize {
                    return Err(misplaced(t, "more than 65535 joints"));
                }
                let end_site = t.text == "End";
                let name = if end_site {
                    let s = need(lex)?;
                    if s.text != "Site" {
                        return Err(misplaced(s, "expected 'Site' after 'End'"));
                    }
                    String::new() // named after parsing, see `name_end_sites`
                } else {
                    let n = need(lex)?;
                    if n.text == "{" || n.text == "}" {
                        return Err(misplaced(n, "expected a joint name"));
                    }
                    if !names.insert(n.text.to_string()) {
                        return Err(BvhError::DuplicateJoint { line: n.line, name: n.text.to_string() });
                    }
                    n.text.to_string()
                };
                open_brace(lex)?;
                joints.push(RawJoint { name, parent: Some(cur), offset: [0.0; 3], channels: vec![], end_site });
                stack.push(Open { idx: joints.len() - 1, has_offset: false, has_channels: false });
            }
            "}" => {
                if !top.has_offset {
                    let why = if joints[cur].end_site { "End Site without OFFSET" } else { "joint without OFFSET" };
                    return Err(misplaced(t, why));
                }
                stack.pop();
            }
            "{" | "MOTION" => return Err(BvhError::UnbalancedBraces { line: t.line }),
            _ => return Err(misplaced(t, "")),
        }
    }
    name_end_sites(&mut joints);
    Ok(joints)
}

/// End sites are named `<parent>_End` (made unique with a numeric suffix if needed).
fn name_end_sites(joints: &mut [RawJoint]) {
    let mut used: std::collections::HashSet<String> =
        joints.iter().filter(|j| !j.end_site).map(|j| j.name.clone()).collect();
    for i in 0..joints.len() {
        if !joints[i].end_site {
            continue;
        }
        let parent = joints[i].parent.map(|p| joints[p].name.clone()).unwrap_or_default();
        let mut name = format!("{parent}_End");
        let mut k = 2;
        while used.contains(&name) {
            name = format!("{parent}_End{k}");
            k += 1;
        }
        used.insert(name.clone());
        joints[i].name = name;
    }
}

/// Number of data rows after the `Frame Time` line when there are no channels at all: lines
/// after that line, not counting the empty remainder after a final newline.
fn count_empty_rows(rest: &str) -> usize {
    let mut lines: Vec<&str> = rest.split('\n').skip(1).collect();
    if lines.last().is_some_and(|l| l.trim().is_empty()) {
        lines.pop();
    }
    lines.len()
}

/// Parses a whole BVH text.
pub(crate) fn parse(text: &str, mode: Mode) -> Result<Parsed, BvhError> {
    let mut lex = Lexer::new(text);
    let joints = parse_hierarchy(&mut lex)?;
    let nch: usize = joints.iter().map(|j| j.channels.len()).sum();

    // MOTION header.
    let t = lex.next_tok().ok_or(BvhError::NoFrames { line: lex.last_line })?;
    match t.text {
        "MOTION" => {}
        "}" => return Err(BvhError::UnbalancedBraces { line: t.line }),
        "ROOT" => return Err(misplaced(t, "only one ROOT is supported")),
        _ => return Err(misplaced(t, "expected MOTION")),
    }
    let t = lex.next_tok().ok_or(BvhError::NoFrames { line: lex.last_line })?;
    let count_tok = if t.text == "Frames:" {
        lex.next_tok().ok_or(BvhError::NoFrames { line: lex.last_line })?
    } else if let Some(rest) = t.text.strip_prefix("Frames:") {
        Tok { text: rest, line: t.line }
    } else {
        return Err(misplaced(t, "expected Frames:"));
    };
    let declared: usize = count_tok
        .text
        .parse()
        .map_err(|_| BvhError::BadNumber { line: count_tok.line, text: count_tok.text.to_string() })?;
    let frames_line = count_tok.line;
    let t = lex.next_tok().ok_or(BvhError::BadFrameTime { line: lex.last_line, text: "end of file".into() })?;
    if t.text != "Frame" {
        return Err(BvhError::BadFrameTime { line: t.line, text: t.text.to_string() });
    }
    let t = lex.next_tok().ok_or(BvhError::BadFrameTime { line: lex.last_line, text: "end of file".into() })?;
    let ft_tok = if t.text == "Time:" {
        lex.next_tok().ok_or(BvhError::BadFrameTime { line: lex.last_line, text: "end of file".into() })?
    } else if let Some(rest) = t.text.strip_prefix("Time:") {
        Tok { text: rest, line: t.line }
    } else {
        return Err(BvhError::BadFrameTime { line: t.line, text: t.text.to_string() });
    };
    let frame_time = match ft_tok.text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => v,
        _ => return Err(BvhError::BadFrameTime { line: ft_tok.line, text: ft_tok.text.to_string() }),
    };
    if declared == 0 && mode != Mode::Inspect {
        return Err(BvhError::NoFrames { line: frames_line });
    }

    // Values.
    let mut values = Vec::new();
    let (frames, rows_present, trailing);
    if nch == 0 {
        let rows = count_empty_rows(lex.rest());
        // Any tokens here are stray values; they cannot belong to a row.
        let mut stray = 0;
        while lex.next_tok().is_some() {
            stray += 1;
        }
        rows_present = rows;
        trailing = stray;
        frames = match mode {
            Mode::Strict if rows < declared => {
                return Err(BvhError::Truncated { line: lex.last_line, declared, found: rows });
            }
            Mode::Strict => declared,
            _ => rows,
        };
    } else {
        let need = declared.saturating_mul(nch);
        let mut extra = 0usize;
        while let Some(t) = lex.next_tok() {
            if mode == Mode::Strict && values.len() >= need {
                extra += 1; // beyond the declared frames: counted, not parsed
                continue;
            }
            values.push(parse_num(t)?);
        }
        let total = values.len() + extra;
        rows_present = total / nch;
        trailing = total % nch;
        frames = match mode {
            Mode::Strict if values.len() < need => {
                return Err(BvhError::Truncated { line: lex.last_line, declared, found: values.len() / nch });
            }
            Mode::Strict => declared,
            _ => values.len() / nch,
        };
        values.truncate(frames * nch);
    }
    if frames == 0 && mode != Mode::Inspect {
        return Err(BvhError::NoFrames { line: frames_line });
    }
    Ok(Parsed { joints, channels: nch, declared, frame_time, frames, values, rows_present, trailing })
}
