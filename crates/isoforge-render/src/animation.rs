//! Animations: a run of pictures as an animated GIF, by the `image` crate's GIF encoder
//! (colours reduced per frame by NeuQuant).

use std::io::Write;

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};

use crate::Image;

/// NeuQuant's sampling factor, 1 (best) to 30 (fastest). 10 is the encoder's default
/// trade-off: a 400 x 300 frame in about 20 ms, with no visible banding on the renderer's
/// smooth shading.
const QUANTIZER_SPEED: i32 = 10;

/// A looping GIF being written frame by frame (frames are encoded as they come, so a
/// long animation is never held in memory).
pub struct GifWriter<'w> {
    encoder: GifEncoder<&'w mut dyn Write>,
    delay_ms: u32,
}

impl<'w> GifWriter<'w> {
    /// Starts a looping GIF that shows each frame for `delay_ms`.
    pub fn new(w: &'w mut dyn Write, delay_ms: u32) -> std::io::Result<GifWriter<'w>> {
        let mut encoder = GifEncoder::new_with_speed(w, QUANTIZER_SPEED);
        encoder
            .set_repeat(Repeat::Infinite)
            .map_err(std::io::Error::other)?;
        Ok(GifWriter { encoder, delay_ms })
    }

    /// Adds a frame (all frames the same size).
    pub fn push(&mut self, f: &Image) -> std::io::Result<()> {
        let rgba: Vec<u8> = f
            .pixels
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        let Some(buffer) = RgbaImage::from_raw(f.width, f.height, rgba) else {
            return Err(std::io::Error::other("a frame's pixels do not fill it"));
        };
        let frame = Frame::from_parts(buffer, 0, 0, Delay::from_numer_denom_ms(self.delay_ms, 1));
        self.encoder
            .encode_frame(frame)
            .map_err(std::io::Error::other)
    }
}

/// Writes `frames` (all the same size) as a looping GIF showing each for `delay_ms`.
pub fn write_gif(frames: &[Image], delay_ms: u32, w: &mut dyn Write) -> std::io::Result<()> {
    let mut gif = GifWriter::new(w, delay_ms)?;
    for f in frames {
        gif.push(f)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_through_a_gif() {
        let frames = [
            Image::filled(8, 6, [200, 30, 30]),
            Image::filled(8, 6, [30, 30, 200]),
            Image::filled(8, 6, [30, 200, 30]),
        ];
        let mut bytes = Vec::new();
        write_gif(&frames, 100, &mut bytes).unwrap();
        assert!(bytes.starts_with(b"GIF89a"));
        // The image crate reads it back: three frames of the same size and colours.
        let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(&bytes)).unwrap();
        use image::AnimationDecoder;
        let back: Vec<_> = decoder.into_frames().collect::<Result<_, _>>().unwrap();
        assert_eq!(back.len(), 3);
        for (f, want) in back.iter().zip(&frames) {
            let px = f.buffer().get_pixel(4, 3).0;
            let w = want.pixel(4, 3);
            assert!(
                (0..3).all(|k| (px[k] as i32 - w[k] as i32).abs() <= 8),
                "{px:?} vs {w:?}"
            );
            assert_eq!(f.delay().numer_denom_ms(), (100, 1));
        }
    }
}
