//! Viewpoints, and the model as seen from one: world coordinates turned into view
//! coordinates `(u, v, w)`, u to the right, v up, w toward the viewer.

use glam::DVec3;
use isoforge_field::{Bounds, ClippedField, GradEval, Interval, IntervalEval, PointEval};

/// Where the picture is taken from.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum View {
    /// From the front, right and above (x right-ish, z up).
    #[default]
    Iso,
    /// From above, looking down -z (x right, y up).
    Top,
    /// From the front, looking along +y (x right, z up).
    Front,
    /// From the right, looking along -x (y right, z up).
    Right,
}

impl View {
    /// Every view, for callers that offer a choice.
    pub const ALL: [View; 4] = [View::Iso, View::Top, View::Front, View::Right];

    /// The view for a name: `iso`, `top`, `front`, `right` (any case).
    pub fn from_name(name: &str) -> Option<View> {
        match name.to_ascii_lowercase().as_str() {
            "iso" => Some(View::Iso),
            "top" => Some(View::Top),
            "front" => Some(View::Front),
            "right" => Some(View::Right),
            _ => None,
        }
    }

    /// The view axes in world coordinates: `u` (right), `v` (up), `w` (toward the viewer),
    /// a right-handed orthonormal frame.
    pub(crate) fn frame(self) -> [DVec3; 3] {
        let (w, up) = match self {
            View::Top => (DVec3::Z, DVec3::Y),
            View::Front => (DVec3::NEG_Y, DVec3::Z),
            View::Right => (DVec3::X, DVec3::Z),
            View::Iso => (DVec3::new(1.0, -1.0, 1.0).normalize(), DVec3::Z),
        };
        let u = up.cross(w).normalize();
        let v = w.cross(u);
        [u, v, w]
    }
}

/// The model clipped to its region, evaluated in view coordinates: a view point
/// `(u, v, w)` is the world point `centre + u·U + v·V + w·W`. Every view, the isometric
/// one included, then looks straight down -w.
#[derive(Clone)]
pub(crate) struct ViewField {
    field: ClippedField,
    /// The view axes U, V, W in world coordinates.
    axes: [DVec3; 3],
    /// The region's centre, the view origin.
    centre: DVec3,
}

impl ViewField {
    pub(crate) fn new(field: ClippedField, view: View) -> Self {
        let b = field.bounds();
        let centre = (DVec3::from(b.min) + DVec3::from(b.max)) * 0.5;
        ViewField {
            field,
            axes: view.frame(),
            centre,
        }
    }

    /// The region's extent along each view axis: `[lo, hi]` for u, v and w.
    pub(crate) fn extent(&self) -> [[f64; 2]; 3] {
        let b: &Bounds = self.field.bounds();
        let half = (DVec3::from(b.max) - DVec3::from(b.min)) * 0.5;
        let mut out = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
        for k in 0..8 {
            let corner = DVec3::select(
                glam::BVec3::new(k & 1 == 1, k & 2 == 2, k & 4 == 4),
                half,
                -half,
            );
            for (range, axis) in out.iter_mut().zip(self.axes) {
                let c = axis.dot(corner);
                range[0] = range[0].min(c);
                range[1] = range[1].max(c);
            }
        }
        out
    }

    fn world(&self, p: [f64; 3]) -> [f64; 3] {
        let [u, v, w] = self.axes;
        (self.centre + u * p[0] + v * p[1] + w * p[2]).to_array()
    }

    /// F at a view point.
    pub(crate) fn point(&self, ev: &mut PointEval, p: [f64; 3]) -> f64 {
        self.field.point(ev, self.world(p))
    }

    /// An enclosure of F over a view box: the world box is found by interval arithmetic on
    /// the same affine map, so it encloses the rotated view box.
    pub(crate) fn interval(&self, ev: &mut IntervalEval, b: [Interval; 3]) -> Interval {
        let [u, v, w] = self.axes;
        let c = self.centre;
        let k = |c: f64| Interval::try_from((c, c)).unwrap_or(Interval::ENTIRE);
        let world = [0, 1, 2].map(|a| b[0] * k(u[a]) + b[1] * k(v[a]) + b[2] * k(w[a]) + k(c[a]));
        self.field.interval(ev, world)
    }

    /// F and its gradient in view coordinates at a view point.
    pub(crate) fn grad(&self, ev: &mut GradEval, p: [f64; 3]) -> (f64, DVec3) {
        let g = self.field.grad(ev, self.world(p));
        let d = DVec3::from(g.d);
        let [u, v, w] = self.axes;
        (g.v, DVec3::new(u.dot(d), v.dot(d), w.dot(d)))
    }

    /// The field simplified by the choices of `ev`'s last [`ViewField::interval`] call.
    pub(crate) fn narrow(&self, ev: &IntervalEval) -> ViewField {
        ViewField {
            field: self.field.narrow(ev),
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_right_handed_orthonormal_frames() {
        for view in View::ALL {
            let [u, v, w] = view.frame();
            assert!((u.cross(v) - w).length() < 1e-12, "{view:?}");
            for a in [u, v, w] {
                assert!((a.length() - 1.0).abs() < 1e-12, "{view:?}");
            }
            assert!(v.z >= 0.0, "{view:?}: up is up");
        }
    }

    #[test]
    fn each_view_looks_from_its_side() {
        assert_eq!(View::Top.frame()[2], DVec3::Z);
        assert_eq!(View::Front.frame()[2], DVec3::NEG_Y);
        assert_eq!(View::Right.frame()[2], DVec3::X);
        let iso = View::Iso.frame()[2];
        assert!(iso.x > 0.0 && iso.y < 0.0 && iso.z > 0.0);
        assert_eq!(View::from_name("TOP"), Some(View::Top));
        assert_eq!(View::from_name("side"), None);
    }

    #[test]
    fn view_and_world_agree() {
        // An off-centre ball in an off-centre region: F at a view point equals F at the
        // world point it stands for, and the view interval encloses it.
        let (x, y, z) = (
            isoforge_field::Shape::x(),
            isoforge_field::Shape::y(),
            isoforge_field::Shape::z(),
        );
        let ball = (x - 2.0).square() + (y + 1.0).square() + (z - 0.5).square() - 1.0;
        let region = Bounds::new([0.5, -2.5, -1.0], [3.5, 0.5, 2.0]).unwrap();
        let field = ClippedField::new(&ball, region);
        let mut pe = PointEval::new();
        let mut ie = IntervalEval::new();
        for view in View::ALL {
            let vf = ViewField::new(field.clone(), view);
            for p in [[0.0, 0.0, 0.0], [0.3, -0.2, 0.7], [1.4, 1.0, -0.4]] {
                let world = vf.world(p);
                assert_eq!(vf.point(&mut pe, p), field.point(&mut pe, world));
                let b = p.map(|c| Interval::try_from((c - 0.1, c + 0.1)).unwrap());
                let i = vf.interval(&mut ie, b);
                let f = vf.point(&mut pe, p);
                assert!(i.inf() <= f && f <= i.sup(), "{view:?} {p:?}");
            }
        }
    }
}
