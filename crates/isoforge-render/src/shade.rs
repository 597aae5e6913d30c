//! Shading: a hit's colour from the surface normal (Lambert, one key light plus ambient).

use glam::DVec3;

/// Background colour (a light gray with a hint of blue).
pub const BACKGROUND: [f64; 3] = [0.95, 0.96, 0.98];
/// The model's colour: a calm gray-blue.
const BASE: [f64; 3] = [0.52, 0.62, 0.78];
/// Ambient light share; the key light gives the rest.
const AMBIENT: f64 = 0.28;
/// The key light's direction in view space: from the upper left, in front.
const LIGHT: DVec3 = DVec3::new(-0.45, 0.55, 0.7);

/// A colour as 8-bit RGB.
pub fn to_rgb(c: [f64; 3]) -> [u8; 3] {
    c.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// The colour of a surface whose outward normal (view space) is along `gradient`. A NaN
/// or zero gradient (a crease, a singular point) is taken to face the viewer.
pub fn shade(gradient: DVec3) -> [f64; 3] {
    let n = gradient.try_normalize().unwrap_or(DVec3::Z);
    let lambert = n.dot(LIGHT.normalize()).max(0.0);
    BASE.map(|c| c * (AMBIENT + (1.0 - AMBIENT) * lambert))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn luminance(c: [f64; 3]) -> f64 {
        c.iter().sum()
    }

    #[test]
    fn facing_the_light_is_brightest_and_away_is_ambient() {
        let lit = shade(LIGHT);
        let away = shade(-LIGHT);
        assert!(luminance(lit) > luminance(shade(DVec3::Z)));
        assert!(luminance(shade(DVec3::Z)) > luminance(away));
        assert_eq!(away, BASE.map(|c| c * AMBIENT));
        // Only the direction matters.
        assert_eq!(shade(DVec3::new(0.0, 3.0, 0.0)), shade(DVec3::Y));
    }

    #[test]
    fn undefined_normals_face_the_viewer() {
        assert_eq!(shade(DVec3::ZERO), shade(DVec3::Z));
        assert_eq!(shade(DVec3::splat(f64::NAN)), shade(DVec3::Z));
        assert_eq!(shade(DVec3::new(f64::INFINITY, 0.0, 0.0)), shade(DVec3::Z));
    }
}
