//! The picture: RGB pixels, and its PNG encoding.

/// An RGB picture, 8 bits a channel, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes, row by row, red green blue.
    pub pixels: Vec<u8>,
}

impl Image {
    /// A picture of one colour.
    pub fn filled(width: u32, height: u32, rgb: [u8; 3]) -> Self {
        let n = width as usize * height as usize;
        Image {
            width,
            height,
            pixels: rgb.repeat(n),
        }
    }

    /// The colour at a pixel.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }

    /// Copies `rgb`, the rows of a `w`-pixel-wide block, to the picture with its top-left
    /// pixel at `(x0, y0)`.
    pub(crate) fn paste(&mut self, x0: u32, y0: u32, w: u32, rgb: &[u8]) {
        let width = self.width as usize;
        for (row, chunk) in rgb.chunks_exact(w as usize * 3).enumerate() {
            let y = y0 as usize + row;
            let start = (y * width + x0 as usize) * 3;
            self.pixels[start..start + chunk.len()].copy_from_slice(chunk);
        }
    }

    /// Encodes the picture as a PNG.
    pub fn write_png(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut enc = png::Encoder::new(w, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(&self.pixels)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paste_places_a_block_and_png_round_trips() {
        let mut img = Image::filled(4, 3, [9, 9, 9]);
        img.paste(1, 1, 2, &[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
        assert_eq!(img.pixel(0, 0), [9, 9, 9]);
        assert_eq!(img.pixel(1, 1), [1, 2, 3]);
        assert_eq!(img.pixel(2, 1), [4, 5, 6]);
        assert_eq!(img.pixel(1, 2), [7, 8, 9]);
        assert_eq!(img.pixel(3, 2), [9, 9, 9]);
        let mut bytes = Vec::new();
        img.write_png(&mut bytes).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (4, 3));
        assert_eq!(&buf[..info.buffer_size()], &img.pixels[..]);
    }
}
