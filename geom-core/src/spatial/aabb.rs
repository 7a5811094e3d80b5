//! [`Aabb`]: an axis-aligned bounding box with closed bounds.

use serde::{Deserialize, Serialize};

use crate::math::{AsPt3, Pt3, Vec3};

/// An axis-aligned box `[min.x, max.x] × [min.y, max.y] × [min.z, max.z]` (closed: points on the
/// boundary are inside, boxes that touch overlap).
///
/// The empty box has `min = +∞`, `max = −∞`, so that [`Aabb::union`] and [`Aabb::extend`] need no
/// special case. Units are those of the points (metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower corner.
    pub min: Pt3,
    /// Upper corner.
    pub max: Pt3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::empty()
    }
}

impl Aabb {
    /// A box from its two corners (no reordering: `min` must not exceed `max` for a non-empty box).
    pub fn new(min: Pt3, max: Pt3) -> Self {
        Self { min, max }
    }

    /// The empty box (`min = +∞`, `max = −∞`): contains nothing, overlaps nothing, and is the
    /// identity of [`Aabb::union`].
    pub fn empty() -> Self {
        Self { min: Pt3::from([f64::INFINITY; 3]), max: Pt3::from([f64::NEG_INFINITY; 3]) }
    }

    /// The smallest box holding all `points` (empty for no points).
    pub fn from_points<P: AsPt3>(points: &[P]) -> Self {
        let mut b = Self::empty();
        for p in points {
            b.extend(&p.pt3());
        }
        b
    }

    /// `true` if the box holds no point (some `min > max`, or a NaN bound).
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// The smallest box holding both boxes.
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.inf(&other.min), max: self.max.sup(&other.max) }
    }

    /// Grows the box to hold `p`.
    #[inline]
    pub fn extend(&mut self, p: &Pt3) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    /// The box grown by `margin` on every side (a negative margin shrinks it; the result may be
    /// empty). The empty box stays empty.
    #[inline]
    pub fn grow(&self, margin: f64) -> Aabb {
        let m = Vec3::repeat(margin);
        Aabb { min: self.min - m, max: self.max + m }
    }

    /// `true` if `p` lies in the closed box.
    #[inline]
    pub fn contains(&self, p: &Pt3) -> bool {
        (0..3).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }

    /// `true` if the closed boxes share a point (touching boxes overlap). Exact: only comparisons.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        (0..3).all(|k| self.min[k] <= other.max[k] && other.min[k] <= self.max[k])
    }

    /// Length of the diagonal, 0 for the empty box.
    #[inline]
    pub fn diag(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            (self.max - self.min).norm()
        }
    }

    /// Side lengths (zero vector for the empty box).
    #[inline]
    pub fn size(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::zeros()
        } else {
            self.max - self.min
        }
    }

    /// The centre point (meaningless, non-finite, for the empty box).
    pub fn center(&self) -> Pt3 {
        nalgebra::center(&self.min, &self.max)
    }

    /// Index (0, 1, 2) of the longest side; ties go to the lower axis.
    pub fn longest_axis(&self) -> usize {
        let s = self.size();
        let mut k = 0;
        for j in 1..3 {
            if s[j] > s[k] {
                k = j;
            }
        }
        k
    }

    /// Squared Euclidean distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: &Pt3) -> f64 {
        let mut d2 = 0.0;
        for k in 0..3 {
            let d = (self.min[k] - p[k]).max(p[k] - self.max[k]).max(0.0);
            d2 += d * d;
        }
        d2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_is_union_identity_and_overlaps_nothing() {
        let b = Aabb::new(Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 2.0, 3.0));
        let e = Aabb::empty();
        assert!(e.is_empty());
        assert_eq!(e.union(&b), b);
        assert!(!e.overlaps(&b) && !b.overlaps(&e));
        assert_eq!(e.diag(), 0.0);
        assert!(e.grow(1.0).is_empty());
    }

    #[test]
    fn touching_boxes_overlap_and_points_on_faces_are_inside() {
        let a = Aabb::new(Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 1.0));
        let b = Aabb::new(Pt3::new(1.0, 0.5, 0.5), Pt3::new(2.0, 2.0, 2.0));
        let c = Aabb::new(Pt3::new(1.0 + 1e-12, 0.5, 0.5), Pt3::new(2.0, 2.0, 2.0));
        assert!(a.overlaps(&b));
        assert!(!a.overlaps(&c));
        assert!(a.contains(&Pt3::new(1.0, 0.0, 0.5)));
        assert!(!a.contains(&Pt3::new(1.0, -1e-300, 0.5)));
    }

    #[test]
    fn from_points_grow_diag_center() {
        let b = Aabb::from_points(&[[1.0, -1.0, 2.0], [3.0, 1.0, 2.0], [2.0, 0.0, 6.0]]);
        assert_eq!(b.min, Pt3::new(1.0, -1.0, 2.0));
        assert_eq!(b.max, Pt3::new(3.0, 1.0, 6.0));
        assert_eq!(b.center(), Pt3::new(2.0, 0.0, 4.0));
        assert_eq!(b.diag(), (4.0f64 + 4.0 + 16.0).sqrt());
        assert_eq!(b.longest_axis(), 2);
        let g = b.grow(0.5);
        assert_eq!(g.min, Pt3::new(0.5, -1.5, 1.5));
        assert_eq!(b.distance_squared(&Pt3::new(0.0, 0.0, 0.0)), 1.0 + 4.0);
        assert_eq!(b.distance_squared(&Pt3::new(2.0, 0.0, 3.0)), 0.0);
    }

    #[test]
    fn serde_round_trip() {
        let b = Aabb::new(Pt3::new(0.25, -1.0, 3.5), Pt3::new(1.0, 2.0, 4.0));
        let s = serde_json::to_string(&b).expect("serialisable");
        let back: Aabb = serde_json::from_str(&s).expect("parsable");
        assert_eq!(b, back);
    }
}
