//! A hull's supporting planes, grouped by the direction they face, for the largest signed
//! distance to them at a point without visiting every plane.
//!
//! A sampled part's hull has about 1,300 facets, and its field (the largest plane value
//! inside, the nearest facet outside) visited all of them at every point: a mesh of such
//! a hull spent nearly all its time there. Each group holds the planes whose normals lie
//! in a cone around one of 42 directions; over a group, `n · p − h` is at most
//! `|q| cos(max(0, θ − α)) − min(h − n · o)` with `q = p − o` (`o` the body's centre,
//! `θ` the angle from the cone's axis to `q`, `α` the cone's half-angle). A group whose
//! bound is below the best value found is skipped: near the surface only the groups
//! facing the point are read.

use std::ops::Range;

use glam::DVec3;

use super::polytope::sphere_directions;

/// Fewer planes than this are read one by one: a bound per group costs as much as a few
/// planes.
const GROUPED_FROM: usize = 64;

/// Group axes: level 1 of the icosphere, 42 directions.
const AXIS_LEVEL: u32 = 1;
const AXES: usize = 42;

/// One cone of normals.
#[derive(Clone, Debug)]
struct Group {
    axis: DVec3,
    /// Cosine and sine of the widest angle between the axis and a member's normal.
    cos_half: f64,
    sin_half: f64,
    /// The least `h − n · o` of the members.
    lowest: f64,
    members: Range<usize>,
}

/// A point relative to the groups' origin.
pub struct Seen {
    q: DVec3,
    rho: f64,
}

/// Planes `n · p = h` (n unit, outward), struct-of-arrays, ordered group by group.
#[derive(Clone, Debug, Default)]
pub struct PlaneSet {
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    h: Vec<f64>,
    origin: DVec3,
    groups: Vec<Group>,
    /// Added to every group's bound for rounding: far below any distance that matters.
    slack: f64,
}

impl PlaneSet {
    /// The planes, grouped about `origin` (any point; the body's centre gives the
    /// tightest bounds). Returns the set and, for each of its planes in order, the index
    /// it had in `planes`.
    pub fn new(planes: &[(DVec3, f64)], origin: DVec3) -> (PlaneSet, Vec<usize>) {
        let axes = if planes.len() >= GROUPED_FROM {
            sphere_directions(AXIS_LEVEL)
        } else {
            vec![DVec3::Z]
        };
        let nearest_axis = |n: DVec3| {
            (0..axes.len())
                .max_by(|&a, &b| axes[a].dot(n).total_cmp(&axes[b].dot(n)))
                .unwrap_or(0)
        };
        let mut order: Vec<(usize, usize)> = planes
            .iter()
            .enumerate()
            .map(|(i, (n, _))| (nearest_axis(*n), i))
            .collect();
        order.sort_unstable();
        let scale = planes
            .iter()
            .map(|(_, h)| h.abs())
            .fold(origin.length(), f64::max);
        let mut set = PlaneSet {
            origin,
            slack: 1e-9 * scale.max(1e-9),
            ..PlaneSet::default()
        };
        let mut start = 0;
        while start < order.len() {
            let axis_index = order[start].0;
            let end = start + order[start..].partition_point(|&(a, _)| a == axis_index);
            let axis = if axes.len() == 1 {
                DVec3::Z
            } else {
                axes[axis_index]
            };
            let mut group = Group {
                axis,
                cos_half: 1.0,
                sin_half: 0.0,
                lowest: f64::INFINITY,
                members: start..end,
            };
            for &(_, i) in &order[start..end] {
                let (n, h) = planes[i];
                group.cos_half = group.cos_half.min(n.dot(axis));
                group.lowest = group.lowest.min(h - n.dot(origin));
                set.nx.push(n.x);
                set.ny.push(n.y);
                set.nz.push(n.z);
                set.h.push(h);
            }
            if axes.len() == 1 {
                // One group: no bound to speak of (the cone may be the whole sphere).
                group.cos_half = -1.0;
            }
            // A little wider than measured, for rounding.
            group.cos_half = (group.cos_half - 1e-9).max(-1.0);
            group.sin_half = (1.0 - group.cos_half * group.cos_half).max(0.0).sqrt();
            set.groups.push(group);
            start = end;
        }
        let moved = order.into_iter().map(|(_, i)| i).collect();
        (set, moved)
    }

    /// How many planes.
    pub fn len(&self) -> usize {
        self.h.len()
    }

    /// True without planes.
    pub fn is_empty(&self) -> bool {
        self.h.is_empty()
    }

    /// Plane `i`'s unit normal.
    pub fn normal(&self, i: usize) -> DVec3 {
        DVec3::new(self.nx[i], self.ny[i], self.nz[i])
    }

    /// `n · p − h` for plane `i`.
    pub fn value(&self, i: usize, p: DVec3) -> f64 {
        self.nx[i] * p.x + self.ny[i] * p.y + self.nz[i] * p.z - self.h[i]
    }

    /// At least the largest `n · p − h` over group `g`'s planes.
    fn bound(&self, g: &Group, q: DVec3, rho: f64) -> f64 {
        let reach = if rho == 0.0 {
            0.0
        } else {
            let cos_t = (g.axis.dot(q) / rho).clamp(-1.0, 1.0);
            if cos_t >= g.cos_half {
                rho
            } else {
                // cos(θ − α), θ the angle from the axis to q.
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                rho * (cos_t * g.cos_half + sin_t * g.sin_half)
            }
        };
        reach - g.lowest + self.slack
    }

    /// The largest `n · p − h` over the planes and its plane's index (the lowest of
    /// equals); `(-inf, 0)` without planes.
    pub fn max(&self, p: DVec3) -> (f64, usize) {
        let mut best = (f64::NEG_INFINITY, 0);
        if self.groups.len() == 1 {
            self.scan(0..self.len(), p, &mut best);
            return best;
        }
        let q = p - self.origin;
        let rho = q.length();
        // The group with the highest bound first: it holds the answer near the surface,
        // and its value lets the others be skipped.
        let mut bounds = [f64::NEG_INFINITY; AXES];
        for (b, g) in bounds.iter_mut().zip(&self.groups) {
            *b = self.bound(g, q, rho);
        }
        let first = (0..self.groups.len())
            .max_by(|&a, &b| bounds[a].total_cmp(&bounds[b]))
            .unwrap_or(0);
        self.scan(self.groups[first].members.clone(), p, &mut best);
        for (k, g) in self.groups.iter().enumerate() {
            if k != first && bounds[k] >= best.0 {
                self.scan(g.members.clone(), p, &mut best);
            }
        }
        best
    }

    /// Ties go to the lowest index, so the answer does not depend on the order groups
    /// are read in.
    fn scan(&self, range: Range<usize>, p: DVec3, best: &mut (f64, usize)) {
        for i in range {
            let d = self.value(i, p);
            if d > best.0 || d == best.0 && i < best.1 {
                *best = (d, i);
            }
        }
    }

    /// `p` as the group bounds see it.
    pub fn seen_from_origin(&self, p: DVec3) -> Seen {
        let q = p - self.origin;
        Seen { q, rho: q.length() }
    }

    /// False when no plane of group `g` has `n · p − h > floor`.
    pub fn may_exceed(&self, g: usize, p: &Seen, floor: f64) -> bool {
        self.groups.len() == 1 || self.bound(&self.groups[g], p.q, p.rho) > floor
    }

    /// Every group: (index, planes).
    pub fn groups(&self) -> impl Iterator<Item = (usize, Range<usize>)> + '_ {
        self.groups
            .iter()
            .enumerate()
            .map(|(k, g)| (k, g.members.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Any planes, any origin, any point: the grouped max is the linear one, and
        /// every plane above a floor is in a group `may_exceed` keeps.
        #[test]
        fn grouped_max_is_the_linear_max_for_any_planes(
            raw in proptest::collection::vec(
                ([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], -5.0..5.0f64), 1..300),
            origin in [-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64],
            p in [-20.0..20.0f64, -20.0..20.0f64, -20.0..20.0f64],
            below in 0.0..3.0f64,
        ) {
            let planes: Vec<(DVec3, f64)> = raw
                .iter()
                .filter_map(|(n, h)| DVec3::from(*n).try_normalize().map(|n| (n, *h)))
                .collect();
            prop_assume!(!planes.is_empty());
            let (set, _) = PlaneSet::new(&planes, DVec3::from(origin));
            let p = DVec3::from(p);
            let linear = planes
                .iter()
                .map(|(n, h)| n.dot(p) - h)
                .fold(f64::NEG_INFINITY, f64::max);
            let (v, i) = set.max(p);
            prop_assert!((v - linear).abs() <= 1e-12 * (1.0 + linear.abs()), "{v} against {linear}");
            prop_assert_eq!(set.value(i, p), v);
            let floor = linear - below;
            let seen = set.seen_from_origin(p);
            for (g, members) in set.groups() {
                if !set.may_exceed(g, &seen, floor) {
                    for k in members {
                        prop_assert!(set.value(k, p) <= floor, "plane {} left out", k);
                    }
                }
            }
        }
    }

    fn set_of(n: usize) -> Vec<(DVec3, f64)> {
        // Planes touching an ellipsoid-ish body off the origin.
        let c = DVec3::new(3.0, -1.0, 2.0);
        sphere_directions(3)
            .into_iter()
            .take(n)
            .map(|d| {
                let n = (d * DVec3::new(1.0, 2.0, 0.5)).normalize();
                (n, n.dot(c) + 1.0 + 0.5 * d.x.abs())
            })
            .collect()
    }

    #[test]
    fn grouped_max_is_the_linear_max() {
        for count in [10, 200, 642] {
            let planes = set_of(count);
            let (set, moved) = PlaneSet::new(&planes, DVec3::new(3.0, -1.0, 2.0));
            assert_eq!(set.len(), count);
            for (k, &i) in moved.iter().enumerate() {
                assert_eq!(set.normal(k), planes[i].0);
            }
            for p in sphere_directions(2).iter().flat_map(|&d| {
                [0.0, 0.3, 1.1, 1.6, 4.0, 40.0].map(|r| DVec3::new(3.0, -1.0, 2.0) + d * r)
            }) {
                let linear = planes
                    .iter()
                    .map(|(n, h)| n.dot(p) - h)
                    .fold(f64::NEG_INFINITY, f64::max);
                let (v, i) = set.max(p);
                assert!((v - linear).abs() < 1e-12, "{p}: {v} against {linear}");
                assert!((set.value(i, p) - v).abs() < 1e-15);
                // Every plane above a floor is in a range `above` gives.
                let floor = linear - 0.5;
                let seen = set.seen_from_origin(p);
                let listed: Vec<usize> = set
                    .groups()
                    .filter(|(g, _)| set.may_exceed(*g, &seen, floor))
                    .flat_map(|(_, r)| r)
                    .collect();
                for k in 0..set.len() {
                    if set.value(k, p) > floor {
                        assert!(listed.contains(&k), "{p}: plane {k} left out");
                    }
                }
            }
        }
    }
}
