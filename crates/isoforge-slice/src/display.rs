//! How a resin printer's display turns and mirrors the picture of the bed. Layers are
//! drawn in the bed's frame (columns along x, row 0 at the largest y, x along the
//! display's long side); this module turns such an image into the one the printer's
//! firmware expects, by PrusaSlicer's rule so its archives and ours agree pixel for pixel.
//!
//! The rule, measured on PrusaSlicer 2.5's own SL1 archives of an asymmetric letter F for
//! all eight settings (the command in `tools/sl1-reference.sh`, its orientation and
//! mirror flags varied): a portrait display turns the
//! bed picture a quarter turn counter-clockwise (the bed's x runs up the image), then
//! `display_mirror_x` flips the image's columns and `display_mirror_y` its rows. The SL1
//! (portrait, mirrored in x) therefore shows the bed's x running up the image and its y
//! running right: the bed picture flipped about its anti-diagonal.

/// The display's orientation and mirrors.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct DisplayFrame {
    /// The display stands portrait: the image is the bed picture turned a quarter turn.
    pub portrait: bool,
    /// The image's columns are flipped.
    pub mirror_x: bool,
    /// The image's rows are flipped.
    pub mirror_y: bool,
}

impl DisplayFrame {
    /// The bed picture's size (width, height) for an image of `image` pixels.
    pub fn bed_size(&self, image: [u32; 2]) -> [u32; 2] {
        if self.portrait {
            [image[1], image[0]]
        } else {
            image
        }
    }

    /// The image's size (width, height) for a bed picture of `bed` pixels.
    pub fn image_size(&self, bed: [u32; 2]) -> [u32; 2] {
        // A quarter turn swaps the sides either way.
        self.bed_size(bed)
    }

    /// The display's image of a bed picture `w` × `h` pixels (row-major, one byte each).
    pub fn apply(&self, bed: &[u8], w: u32, h: u32) -> Vec<u8> {
        if *self == DisplayFrame::default() {
            return bed.to_vec();
        }
        let [ow, oh] = self.image_size([w, h]);
        let (w, ow, oh) = (w as usize, ow as usize, oh as usize);
        let mut out = vec![0u8; ow * oh];
        for r in 0..oh {
            let rr = if self.mirror_y { oh - 1 - r } else { r };
            for c in 0..ow {
                let cc = if self.mirror_x { ow - 1 - c } else { c };
                // A counter-clockwise quarter turn: the image's column is the bed's row,
                // and its row counts the bed's columns from the right.
                let (bc, br) = if self.portrait {
                    (oh - 1 - rr, cc)
                } else {
                    (cc, rr)
                };
                out[r * ow + c] = bed[br * w + bc];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 2 bed picture with distinct pixels:
    /// ```text
    /// 1 2 3
    /// 4 5 6
    /// ```
    const BED: [u8; 6] = [1, 2, 3, 4, 5, 6];

    fn frame(portrait: bool, mirror_x: bool, mirror_y: bool) -> DisplayFrame {
        DisplayFrame {
            portrait,
            mirror_x,
            mirror_y,
        }
    }

    #[test]
    fn landscape_mirrors_flip_columns_and_rows() {
        assert_eq!(frame(false, false, false).apply(&BED, 3, 2), BED);
        assert_eq!(
            frame(false, true, false).apply(&BED, 3, 2),
            [3, 2, 1, 6, 5, 4]
        );
        assert_eq!(
            frame(false, false, true).apply(&BED, 3, 2),
            [4, 5, 6, 1, 2, 3]
        );
        assert_eq!(
            frame(false, true, true).apply(&BED, 3, 2),
            [6, 5, 4, 3, 2, 1]
        );
    }

    #[test]
    fn portrait_turns_counter_clockwise_and_the_sl1_transposes() {
        // Turned: the right column (3, 6) becomes the top row.
        assert_eq!(
            frame(true, false, false).apply(&BED, 3, 2),
            [3, 6, 2, 5, 1, 4]
        );
        // The SL1 (portrait, mirrored in x): flipped about the anti-diagonal, the bed's x
        // running up the image and its y to the right.
        assert_eq!(
            frame(true, true, false).apply(&BED, 3, 2),
            [6, 3, 5, 2, 4, 1]
        );
        assert_eq!(
            frame(true, false, true).apply(&BED, 3, 2),
            [1, 4, 2, 5, 3, 6]
        );
        assert_eq!(
            frame(true, true, true).apply(&BED, 3, 2),
            [4, 1, 5, 2, 6, 3]
        );
        assert_eq!(frame(true, true, true).image_size([3, 2]), [2, 3]);
    }
}
