//! The camera: which part of view space each pixel shows, and how finely rays are searched
//! in depth.

/// The mapping from pixels to view space: pixel `(x, y)` (from the top left) covers
/// `u(x)..u(x + 1)` by `v(y + 1)..v(y)`; rays run along -w from `w_hi` down to `w_lo`.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Camera {
    /// View-space u, v of the top-left pixel's corner.
    u0: f64,
    v0: f64,
    /// Size of a pixel in mm.
    pub(crate) px: f64,
    /// Depth range (w) of the region.
    pub(crate) w_lo: f64,
    pub(crate) w_hi: f64,
    /// The finest depth step.
    pub(crate) dw: f64,
}

impl Camera {
    /// A camera showing `u` x `v` (view-space ranges) in an image of `size` pixels with a
    /// 4 % margin, keeping the aspect; the depth range is `w`, searched down to steps of
    /// range / 2^`depth` (`None`: about a pixel).
    pub(crate) fn fit(
        u: [f64; 2],
        v: [f64; 2],
        w: [f64; 2],
        size: (u32, u32),
        depth: Option<u8>,
    ) -> Self {
        let (width, height) = (f64::from(size.0), f64::from(size.1));
        let px = ((u[1] - u[0]) / width).max((v[1] - v[0]) / height) * 1.08;
        let px = if px > 0.0 { px } else { f64::MIN_POSITIVE };
        let depth_bits = depth.map_or_else(
            || ((w[1] - w[0]) / px).log2().ceil().clamp(4.0, 16.0) as i32,
            |d| i32::from(d.clamp(1, 24)),
        );
        Camera {
            u0: 0.5 * (u[0] + u[1]) - px * width * 0.5,
            v0: 0.5 * (v[0] + v[1]) + px * height * 0.5,
            px,
            w_lo: w[0],
            w_hi: w[1],
            dw: (w[1] - w[0]) / f64::from(2u32.pow(depth_bits as u32)),
        }
    }

    /// The u of a pixel column position (fractional: `x + 0.5` is a pixel's centre).
    pub(crate) fn u(&self, x: f64) -> f64 {
        self.u0 + x * self.px
    }

    /// The v of a pixel row position (rows run downward, v upward).
    pub(crate) fn v(&self, y: f64) -> f64 {
        self.v0 - y * self.px
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_centres_the_range_and_keeps_the_aspect() {
        let cam = Camera::fit([-1.0, 1.0], [-0.5, 0.5], [-1.0, 1.0], (200, 100), None);
        // Both ranges fit with the 8 % total margin; the picture's centre is the range's.
        assert!((cam.px - 2.0 / 200.0 * 1.08).abs() < 1e-15);
        assert!(cam.u(100.0).abs() < 1e-12 && cam.v(50.0).abs() < 1e-12);
        assert!(cam.u(0.0) < -1.0 && cam.u(200.0) > 1.0);
        assert!(cam.v(0.0) > 0.5 && cam.v(100.0) < -0.5);
        // About a pixel deep by default; an explicit depth gives range / 2^depth.
        assert!(cam.dw <= cam.px && cam.dw > cam.px / 2.0);
        let fine = Camera::fit([-1.0, 1.0], [-0.5, 0.5], [-1.0, 1.0], (200, 100), Some(10));
        assert_eq!(fine.dw, 2.0 / 1024.0);
    }
}
