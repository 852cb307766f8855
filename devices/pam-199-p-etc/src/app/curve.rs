//! Characteristic linearisation CC (manual 6.3.2, 6.3.3).
//!
//! A [`Curve`] is a list of `N` (x, y) points in 0.01 %, sorted by x. The
//! output is the linear interpolation between the two neighbouring points:
//!
//! ```text
//! y = y0 + (x - x0) * (y1 - y0) / (x1 - x0)        for x0 <= x <= x1
//! ```
//!
//! The manual writes `y = (x - x1) * (y1 - y0) / (x1 - x0) + y1`, which is the
//! same straight line anchored at the right-hand point (x1, y1); it is *not*
//! wrong, just the other form of the two-point equation. This implementation
//! anchors at the left point (x0, y0) and rounds the quotient to the nearest
//! integer (halves away from zero); in exact arithmetic both forms agree, with
//! integers they differ by at most 1 LSB (0.01 %). Outside the end points the
//! output is clamped to the end points' y values.
//!
//! Unsorted or duplicate x values never panic: segments are searched in
//! order, the first segment with `x0 <= x <= x1` is used, and a vertical
//! segment (`x1 == x0`) yields `y0`. Between the end points some segment
//! always contains `x`, sorted or not (the last point at or below `x` is
//! followed by one above it). [`Curve::is_sorted`] lets the configuration
//! layer reject unsorted curves.
//!
//! Layouts (object dictionary):
//!
//! * directional, [`DirectionalCurve`] = `Curve<21>`: OD 0x8006, points
//!   −10..10 in ascending x order, stored as CCB:10 … CCB:1 (points −10..−1),
//!   then CCA:0 … CCA:10 (points 0..10); default x = y = −10000, −9000, …, 10000.
//! * independent, [`IndependentCurve`] = `Curve<11>`: OD 0x8016 / 0x8026,
//!   points 0..10, default x = y = 0, 1000, …, 10000.
//!
//! In both, sub-index `2k + 1` is X and `2k + 2` is Y of array point `k`
//! (see [`Curve::od_get`], [`Curve::od_set`]).
//!
//! With the default points the curve is the identity, so CCMODE = ON alone
//! has no effect (manual 6.3.2).

use super::{div_round, sat_i32};

/// One curve point in 0.01 %.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Point {
    /// Input value.
    pub x: i16,
    /// Output value.
    pub y: i16,
}

/// Which coordinate of a point an OD sub-index addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coord {
    /// The X (input) coordinate.
    X,
    /// The Y (output) coordinate.
    Y,
}

/// A characteristic curve of `N` points (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Curve<const N: usize> {
    points: [Point; N],
}

/// The 21-point curve of the directional mode (OD 0x8006).
pub type DirectionalCurve = Curve<21>;
/// The 11-point curve of one independent channel (OD 0x8016 / 0x8026).
pub type IndependentCurve = Curve<11>;

impl Default for Curve<21> {
    /// The identity curve −10000..10000 in steps of 1000 (OD defaults).
    fn default() -> Self {
        Self::linear(-10_000, 10_000)
    }
}

impl Default for Curve<11> {
    /// The identity curve 0..10000 in steps of 1000 (OD defaults).
    fn default() -> Self {
        Self::linear(0, 10_000)
    }
}

impl<const N: usize> Curve<N> {
    /// A curve from its points (in array order).
    pub const fn new(points: [Point; N]) -> Self {
        Self { points }
    }

    /// The identity curve with `N` points evenly spaced from `x_first` to
    /// `x_last` (y = x). For `N == 1` the single point is `x_first`.
    pub fn linear(x_first: i16, x_last: i16) -> Self {
        let span = i64::from(x_last) - i64::from(x_first);
        let steps = i64::try_from(N.saturating_sub(1)).unwrap_or(1).max(1);
        let points = core::array::from_fn(|k| {
            let k = i64::try_from(k).unwrap_or(0);
            let v = i64::from(x_first) + div_round(span * k, steps);
            let v = i16::try_from(v).unwrap_or(x_first);
            Point { x: v, y: v }
        });
        Self { points }
    }

    /// A curve from exactly `N` `(x, y)` pairs; `None` if the slice has
    /// another length.
    pub fn from_pairs(pairs: &[(i16, i16)]) -> Option<Self> {
        if pairs.len() != N {
            return None;
        }
        let mut points = [Point::default(); N];
        for (p, &(x, y)) in points.iter_mut().zip(pairs) {
            *p = Point { x, y };
        }
        Some(Self { points })
    }

    /// The points in array order.
    pub fn points(&self) -> &[Point; N] {
        &self.points
    }

    /// Replaces point `index`; returns `false` (and changes nothing) if
    /// `index >= N`.
    pub fn set_point(&mut self, index: usize, x: i16, y: i16) -> bool {
        match self.points.get_mut(index) {
            Some(p) => {
                *p = Point { x, y };
                true
            }
            None => false,
        }
    }

    /// Maps an OD sub-index (1-based, X/Y interleaved) to the point index and
    /// coordinate; `None` for 0 or beyond `2 * N`.
    pub fn od_entry(subindex: u8) -> Option<(usize, Coord)> {
        let s = usize::from(subindex).checked_sub(1)?;
        let index = s / 2;
        if index >= N {
            return None;
        }
        Some((index, if s % 2 == 0 { Coord::X } else { Coord::Y }))
    }

    /// Reads the value at an OD sub-index (see [`Curve::od_entry`]).
    pub fn od_get(&self, subindex: u8) -> Option<i16> {
        let (i, c) = Self::od_entry(subindex)?;
        let p = self.points.get(i)?;
        Some(match c {
            Coord::X => p.x,
            Coord::Y => p.y,
        })
    }

    /// Writes the value at an OD sub-index; `false` if the sub-index is out
    /// of range. Values are stored as given (range checks, e.g. 0..10000 for
    /// IND, belong to the OD layer).
    pub fn od_set(&mut self, subindex: u8, value: i16) -> bool {
        let Some((i, c)) = Self::od_entry(subindex) else {
            return false;
        };
        let Some(p) = self.points.get_mut(i) else {
            return false;
        };
        match c {
            Coord::X => p.x = value,
            Coord::Y => p.y = value,
        }
        true
    }

    /// Whether the x values are non-decreasing (duplicates allowed).
    pub fn is_sorted(&self) -> bool {
        self.points.windows(2).all(|w| match w {
            [a, b] => a.x <= b.x,
            _ => true,
        })
    }

    /// Applies the curve to `x` (0.01 %), see the module docs. An empty
    /// curve (`N == 0`) is the identity.
    pub fn apply(&self, x: i32) -> i32 {
        let (Some(first), Some(last)) = (self.points.first(), self.points.last()) else {
            return x;
        };
        if x <= i32::from(first.x) {
            return i32::from(first.y);
        }
        if x >= i32::from(last.x) {
            return i32::from(last.y);
        }
        // From here on `x` is strictly between two `i16`s, so differences
        // of it and of the points fit 17 bits, in `i32` arithmetic (only
        // the interpolation's product, 33 bits, takes 64: one multiply,
        // on a Cortex-M4 one instruction).
        for w in self.points.windows(2) {
            let [p0, p1] = w else { continue };
            let (x0, x1) = (i32::from(p0.x), i32::from(p1.x));
            if x0 <= x && x <= x1 {
                if x1 == x0 {
                    return i32::from(p0.y);
                }
                let (y0, y1) = (i32::from(p0.y), i32::from(p1.y));
                let step = div_round(i64::from(x - x0) * i64::from(y1 - y0), i64::from(x1 - x0));
                return sat_i32(i64::from(y0) + step);
            }
        }
        // Not reached: `first.x < x < last.x` here, so the last point
        // with an x at or below `x` is followed by one above it, and the
        // window of the two contains `x`, sorted points or not.
        i32::from(last.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_curves_are_the_identity() {
        let d = DirectionalCurve::default();
        let i = IndependentCurve::default();
        for x in (-10_000..=10_000).step_by(37) {
            assert_eq!(d.apply(x), x);
        }
        for x in (0..=10_000).step_by(13) {
            assert_eq!(i.apply(x), x);
        }
        assert_eq!(
            d.points()[0],
            Point {
                x: -10_000,
                y: -10_000
            }
        );
        assert_eq!(d.points()[10], Point { x: 0, y: 0 });
        assert_eq!(
            d.points()[20],
            Point {
                x: 10_000,
                y: 10_000
            }
        );
    }

    #[test]
    fn interpolates_at_and_between_points_on_both_sides() {
        // A progressive curve: y = x at the ends, lower in the middle.
        let mut c = DirectionalCurve::default();
        assert!(c.set_point(11, 1_000, 500)); // CCA:1
        assert!(c.set_point(9, -1_000, -200)); // CCB:1
        assert_eq!(c.apply(1_000), 500);
        assert_eq!(c.apply(-1_000), -200);
        // Between CCA:0 (0,0) and CCA:1 (1000,500): y = 0 + 400*500/1000.
        assert_eq!(c.apply(400), 200);
        // Between CCA:1 (1000,500) and CCA:2 (2000,2000):
        // y = 500 + 500 * 1500 / 1000 = 1250.
        assert_eq!(c.apply(1_500), 1_250);
        // Negative side: CCB:2 (-2000,-2000) .. CCB:1 (-1000,-200):
        // y = -2000 + (-1500 + 2000) * (1800) / 1000 = -1100.
        assert_eq!(c.apply(-1_500), -1_100);
        // CCB:1 (-1000,-200) .. CCA:0 (0,0): y = -200 + 250 * 200 / 1000 = -150.
        assert_eq!(c.apply(-750), -150);
    }

    #[test]
    fn the_manuals_right_anchored_form_gives_the_same_values() {
        let c = IndependentCurve::from_pairs(&[
            (0, 0),
            (1_000, 300),
            (2_000, 700),
            (3_000, 1_500),
            (4_000, 2_500),
            (5_000, 3_500),
            (6_000, 4_700),
            (7_000, 6_000),
            (8_000, 7_300),
            (9_000, 8_700),
            (10_000, 10_000),
        ])
        .unwrap();
        // Manual: y = (x - x1) * (y1 - y0) / (x1 - x0) + y1.
        let manual = |x: i32, (x0, y0): (i32, i32), (x1, y1): (i32, i32)| {
            (x - x1) * (y1 - y0) / (x1 - x0) + y1
        };
        assert_eq!(c.apply(2_500), manual(2_500, (2_000, 700), (3_000, 1_500)));
        assert_eq!(c.apply(2_500), 1_100);
        assert_eq!(
            c.apply(6_250),
            manual(6_250, (6_000, 4_700), (7_000, 6_000))
        );
        assert_eq!(c.apply(6_250), 5_025);
    }

    #[test]
    fn rounds_to_nearest_with_a_bent_curve() {
        let mut c = IndependentCurve::default();
        c.set_point(1, 1_000, 3_000);
        // (0,0)..(1000,3000): x = 1 -> 3; x = 333 -> 999; x = 500 -> 1500.
        assert_eq!(c.apply(1), 3);
        assert_eq!(c.apply(333), 999);
        // (1000,3000)..(2000,2000) falling: x = 1001 -> 2999.
        assert_eq!(c.apply(1_001), 2_999);
        assert_eq!(c.apply(1_333), 2_667); // 3000 - 333 = 2667
    }

    #[test]
    fn clamps_beyond_the_end_points() {
        let mut c = IndependentCurve::default();
        c.set_point(0, 500, 1_000);
        c.set_point(10, 9_000, 8_000);
        assert_eq!(c.apply(-10_000), 1_000);
        assert_eq!(c.apply(0), 1_000);
        assert_eq!(c.apply(12_000), 8_000);
        assert_eq!(c.apply(i32::MAX), 8_000);
        let d = DirectionalCurve::default();
        assert_eq!(d.apply(i32::MIN), -10_000);
    }

    /// The interpolation as first written, all in wide integers: what
    /// `apply` must equal after its arithmetic went to 32 bits.
    fn reference(points: &[Point], x: i32) -> i32 {
        let (first, last) = (points[0], points[points.len() - 1]);
        let x = i128::from(x);
        if x <= i128::from(first.x) {
            return i32::from(first.y);
        }
        if x >= i128::from(last.x) {
            return i32::from(last.y);
        }
        for w in points.windows(2) {
            let (x0, x1) = (i128::from(w[0].x), i128::from(w[1].x));
            if x0 <= x && x <= x1 {
                if x0 == x1 {
                    return i32::from(w[0].y);
                }
                let (y0, y1) = (i128::from(w[0].y), i128::from(w[1].y));
                let (n, d) = ((x - x0) * (y1 - y0), x1 - x0);
                let q = (n.abs() + d / 2) / d;
                return (y0 + if n < 0 { -q } else { q }) as i32;
            }
        }
        unreachable!("between the end points a window contains x")
    }

    proptest::proptest! {
        #[test]
        fn apply_equals_the_wide_reference_for_any_points_sorted_or_not(
            xs in proptest::array::uniform11(proptest::num::i16::ANY),
            ys in proptest::array::uniform11(proptest::num::i16::ANY),
            sort: bool,
            x: i32,
            near in -40_000i32..40_000,
        ) {
            let mut xs = xs;
            if sort {
                xs.sort_unstable();
            }
            let points: Vec<(i16, i16)> = xs.iter().copied().zip(ys).collect();
            let c = IndependentCurve::from_pairs(&points).unwrap();
            let pts: Vec<Point> = points.iter().map(|&(x, y)| Point { x, y }).collect();
            for x in [x, near] {
                proptest::prop_assert_eq!(c.apply(x), reference(&pts, x), "x {}", x);
            }
        }
    }

    #[test]
    fn duplicate_and_unsorted_x_do_not_panic() {
        let mut c = IndependentCurve::default();
        // Duplicate x = 2000 at points 2 and 3: vertical segment yields y0.
        c.set_point(3, 2_000, 9_000);
        assert!(c.is_sorted());
        assert_eq!(c.apply(2_000), 2_000);
        // Points 3..4 now span 2000..4000 from 9000 to 4000.
        assert_eq!(c.apply(3_000), 6_500);
        // Unsorted: no panic, bounded output.
        let u = IndependentCurve::from_pairs(&[(5_000, 1); 11]).unwrap();
        assert_eq!(u.apply(100), 1);
        let mut u = IndependentCurve::default();
        u.set_point(5, 9_500, 0);
        assert!(!u.is_sorted());
        for x in (0..=10_000).step_by(250) {
            let y = u.apply(x);
            assert!((0..=10_000).contains(&y));
        }
    }

    #[test]
    fn od_subindices_interleave_x_and_y() {
        let mut c = DirectionalCurve::default();
        assert_eq!(DirectionalCurve::od_entry(0), None);
        assert_eq!(DirectionalCurve::od_entry(1), Some((0, Coord::X))); // CCB:10_X
        assert_eq!(DirectionalCurve::od_entry(0x2A), Some((20, Coord::Y))); // CCA:10_Y
        assert_eq!(DirectionalCurve::od_entry(0x2B), None);
        assert_eq!(c.od_get(0x15), Some(0)); // CCA:0_X
        assert_eq!(c.od_get(0x01), Some(-10_000));
        assert!(c.od_set(0x18, 800)); // CCA:1_Y
        assert_eq!(c.apply(1_000), 800);
        assert!(!c.od_set(0, 1));
        assert_eq!(IndependentCurve::od_entry(0x16), Some((10, Coord::Y)));
        assert_eq!(IndependentCurve::od_entry(0x17), None);
        assert!(IndependentCurve::from_pairs(&[(0, 0)]).is_none());
    }
}
