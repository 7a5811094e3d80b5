//! BVH writer: the stored hierarchy and channel layout, Euler angles extracted per joint in its
//! own channel order (gimbal lock handled by [`quat_to_euler`]), lengths in the chosen unit.

use super::BvhUnits;
use crate::anim::motion::Motion;
use crate::anim::skeleton::{Channel, Skeleton};
use crate::math::{quat_to_euler, wrap_angle, RotOrder, UnitQuat};
use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt::Write;

/// Deeper joints are not indented further (indentation is cosmetic; this bounds the output size).
const MAX_INDENT: usize = 32;

/// Writer options.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhWriteOptions {
    /// Length unit of the output (default centimetres; [`BvhUnits::Auto`] also means
    /// centimetres; a non-positive or non-finite [`BvhUnits::Scale`] falls back to metres).
    pub units: BvhUnits,
    /// Decimals of the angles (degrees) in the frame rows; default 6 (motion-graph.md §2.2), i.e.
    /// ≤ 5e-7° ≈ 8.7e-9 rad per angle. Positions get as many more decimals as the unit is larger
    /// than a centimetre (metres: +2), so their resolution is the same 1e-8 m in every unit.
    /// OFFSETs and the frame time are written with the shortest representation that reads back
    /// exactly.
    pub decimals: usize,
}

impl Default for BvhWriteOptions {
    fn default() -> Self {
        Self { units: BvhUnits::Centimetres, decimals: 6 }
    }
}

/// Joints in depth-first order (children in index order), each with its nesting depth; the
/// layout the file is written in. Iterative, so any depth is fine.
fn dfs_order(s: &Skeleton) -> Vec<(usize, usize)> {
    let n = s.joints.len();
    let mut children = vec![Vec::new(); n];
    for (j, joint) in s.joints.iter().enumerate() {
        if let Some(p) = joint.parent {
            children[p as usize].push(j);
        }
    }
    let mut out = Vec::with_capacity(n);
    let mut stack = vec![(0usize, 0usize)];
    while let Some((j, d)) = stack.pop() {
        if j >= n {
            break;
        }
        out.push((j, d));
        for &c in children[j].iter().rev() {
            stack.push((c, d + 1));
        }
    }
    out
}

/// Joint names usable as single BVH tokens: whitespace and braces become `_`, empty names become
/// `joint<i>`, and a name that collides after this gets its index appended.
fn file_names(s: &Skeleton) -> Vec<String> {
    let mut used = std::collections::HashSet::new();
    s.joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let mut n: String =
                j.name.chars().map(|c| if c.is_whitespace() || c == '{' || c == '}' { '_' } else { c }).collect();
            if n.is_empty() {
                n = format!("joint{i}");
            }
            if !j.end_site && !used.insert(n.clone()) {
                n = format!("{n}_{i}");
                used.insert(n.clone());
            }
            n
        })
        .collect()
}

/// The Euler angles (degrees) of `q` for a joint's rotation channels, in channel order. With
/// three channels the order is theirs; with one or two, the missing axes are appended and their
/// angles dropped: exact for rotations that came from such a file (choosing, of the two Euler
/// solutions, the one whose dropped angle is 0).
fn channel_angles(rot_axes: &[usize], q: &UnitQuat, out: &mut Vec<f64>) {
    out.clear();
    if rot_axes.is_empty() {
        return;
    }
    let mut axes = [0usize; 3];
    axes[..rot_axes.len()].copy_from_slice(rot_axes);
    let mut k = rot_axes.len();
    for a in 0..3 {
        if !rot_axes.contains(&a) && k < 3 {
            axes[k] = a;
            k += 1;
        }
    }
    // `axes` is a permutation of {0, 1, 2} (the parser rejects repeated axes).
    let order = RotOrder::from_axes(axes).unwrap_or(RotOrder::ZYX);
    let mut e = quat_to_euler(order, q);
    if rot_axes.len() < 3 && e[2].abs() > FRAC_PI_2 {
        // The other Tait–Bryan solution (θ1 + π, π − θ2, θ3 + π) is the same rotation and has the
        // dropped third angle near 0 (e.g. `Zrotation Xrotation` with |X| > 90°).
        e = [wrap_angle(e[0] + PI), wrap_angle(PI - e[1]), wrap_angle(e[2] + PI)];
    }
    out.extend(e[..rot_axes.len()].iter().map(|a| a.to_degrees()));
}

/// Writes a motion as BVH text: the hierarchy in depth-first order with every joint's stored
/// channels (end sites as `End Site`), then `Frames`, `Frame Time` and one row per frame.
/// Positions are divided by the unit scale (the root row holds `root_pos − root offset`, so the
/// root OFFSET is written as stored). Reading the result back reproduces joint positions to
/// ≈ 1e-7 m with the default options (motion-graph.md §2.2: ≤ 1e-6 m).
///
/// Data the layout cannot hold is not written: rotations of joints without rotation channels,
/// the root motion if the root has no position channels, extra translations of joints without
/// position channels. Motions read from BVH always fit their layout.
pub fn write(m: &Motion, o: &BvhWriteOptions) -> String {
    let s = &*m.skeleton;
    let scale = match o.units {
        BvhUnits::Auto => 0.01,
        u => match u.scale() {
            Some(x) if x > 0.0 && x.is_finite() => x,
            _ => 1.0,
        },
    };
    let order = dfs_order(s);
    let names = file_names(s);
    let pos_decimals = o.decimals + (scale / 0.01).log10().ceil().clamp(0.0, 20.0) as usize;
    let mut out = String::new();
    out.push_str("HIERARCHY\n");
    // Close braces when the depth decreases.
    let mut open: Vec<usize> = Vec::new(); // depths of open blocks
    let close_to = |out: &mut String, open: &mut Vec<usize>, depth: usize| {
        while open.last().is_some_and(|&d| d >= depth) {
            let d = open.pop().unwrap_or(0);
            let _ = writeln!(out, "{}}}", "\t".repeat(d.min(MAX_INDENT)));
        }
    };
    let has_children: Vec<bool> = {
        let mut h = vec![false; s.joints.len()];
        for j in &s.joints {
            if let Some(p) = j.parent {
                h[p as usize] = true;
            }
        }
        h
    };
    for &(j, d) in &order {
        close_to(&mut out, &mut open, d);
        let joint = &s.joints[j];
        let ind = "\t".repeat(d.min(MAX_INDENT));
        let off = joint.offset / scale;
        if joint.end_site && !has_children[j] && d > 0 {
            let _ = writeln!(out, "{ind}End Site\n{ind}{{\n{ind}\tOFFSET {} {} {}", off.x, off.y, off.z);
        } else {
            let kw = if d == 0 { "ROOT" } else { "JOINT" };
            let _ = writeln!(out, "{ind}{kw} {}\n{ind}{{\n{ind}\tOFFSET {} {} {}", names[j], off.x, off.y, off.z);
            let ch: Vec<&str> = joint.channels.iter().map(|c| c.bvh_name()).collect();
            let _ =
                writeln!(out, "{ind}\tCHANNELS {}{}{}", ch.len(), if ch.is_empty() { "" } else { " " }, ch.join(" "));
        }
        open.push(d);
    }
    close_to(&mut out, &mut open, 0);
    let _ = writeln!(out, "MOTION\nFrames: {}\nFrame Time: {}", m.len(), m.frame_time);

    let nj = s.joints.len();
    let rot_axes: Vec<Vec<usize>> =
        s.joints.iter().map(|j| j.channels.iter().filter(|c| c.is_rotation()).map(|c| c.axis()).collect()).collect();
    let root_offset = s.joints.first().map(|j| j.offset).unwrap_or_default();
    let mut angles = Vec::with_capacity(3);
    let mut row: Vec<String> = Vec::new();
    for f in 0..m.len() {
        row.clear();
        let q = m.frame_rot(f);
        let extra = m.frame_extra(f);
        for &(j, _) in &order {
            let joint = &s.joints[j];
            if joint.channels.is_empty() {
                continue;
            }
            let pos =
                if j == 0 { m.root_pos[f] - root_offset } else { extra.map(|e| e[j]).unwrap_or_default() } / scale;
            channel_angles(&rot_axes[j], &q[j], &mut angles);
            let mut ai = angles.iter();
            for c in &joint.channels {
                row.push(match c {
                    Channel::Xpos | Channel::Ypos | Channel::Zpos => format!("{:.*}", pos_decimals, pos[c.axis()]),
                    _ => format!("{:.*}", o.decimals, ai.next().copied().unwrap_or(0.0)),
                });
            }
        }
        out.push_str(&row.join(" "));
        out.push('\n');
    }
    debug_assert_eq!(m.rot.len(), m.len() * nj);
    out
}
