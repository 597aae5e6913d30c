//! SL1 archives (Prusa SL1 and compatible resin printers), laid out as PrusaSlicer writes
//! them: `config.ini` (what the printer reads), `prusaslicer.ini` (the settings used), one
//! PNG per layer named `<jobDir>00000.png` upward, and a thumbnail.

use std::io::{Seek, Write};

use zip::ZipWriter;
use zip::write::SimpleFileOptions;

use crate::SliceError;
use crate::profile::ResinSettings;
use crate::raster::{LayerImages, encode_png};

/// Seconds for the tilt, lift and settle between two exposures on an SL1 at its fast
/// tilt (PrusaSlicer's estimate for the SL1 is of this order; it only feeds printTime).
const FAST_TILT_SECONDS: f64 = 11.0;

/// Thumbnail size PrusaSlicer puts in SL1 files for the printer's screen.
pub const THUMBNAIL: (u32, u32) = (400, 400);

/// The exposure of layer `k` (0-based): the first exposure, fading linearly to the
/// normal one over `faded_layers` layers.
pub(crate) fn exposure(r: &ResinSettings, k: usize) -> f64 {
    if k == 0 || r.faded_layers == 0 {
        return if k == 0 {
            r.first_exposure_time
        } else {
            r.exposure_time
        };
    }
    if k > r.faded_layers {
        return r.exposure_time;
    }
    let t = k as f64 / (r.faded_layers + 1) as f64;
    r.first_exposure_time + (r.exposure_time - r.first_exposure_time) * t
}

/// The archive's figures.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Sl1Figures {
    /// Estimated print time, s.
    pub print_seconds: f64,
    /// Resin used, ml.
    pub used_ml: f64,
}

/// The figures an SL1 archive states for these layers.
pub(crate) fn figures(images: &LayerImages, r: &ResinSettings) -> Sl1Figures {
    let n = images.layers.len();
    let print_seconds: f64 = (0..n).map(|k| exposure(r, k) + FAST_TILT_SECONDS).sum();
    let used_ml = images
        .areas
        .iter()
        .zip(&images.layers)
        .map(|(a, l)| a * l.height)
        .sum::<f64>()
        / 1000.0;
    Sl1Figures {
        print_seconds,
        used_ml,
    }
}

/// `config.ini`.
pub(crate) fn config_ini(images: &LayerImages, r: &ResinSettings, job: &str) -> String {
    let f = figures(images, r);
    let n = images.layers.len();
    let fade = r.faded_layers.min(n.saturating_sub(1));
    [
        "action = print".to_string(),
        format!("jobDir = {job}"),
        format!("expTime = {}", r.exposure_time),
        format!("expTimeFirst = {}", r.first_exposure_time),
        "fileCreationTimestamp = 1980-01-01 at 00:00:00 UTC".to_string(),
        "hollow = 0".to_string(),
        format!("layerHeight = {}", r.layer_height),
        format!("materialName = {}", r.material_name),
        format!("numFade = {fade}"),
        format!("numFast = {n}"),
        "numSlow = 0".to_string(),
        format!("printProfile = {} isoforge", r.layer_height),
        format!("printTime = {:.3}", f.print_seconds),
        format!("printerModel = {}", r.printer_model),
        format!("printerProfile = {}", r.printer_model),
        "printerVariant = default".to_string(),
        format!(
            "prusaSlicerVersion = isoforge-{}",
            env!("CARGO_PKG_VERSION")
        ),
        format!("usedMaterial = {:.6}", f.used_ml),
    ]
    .join("\n")
        + "\n"
}

/// `prusaslicer.ini`: the settings in PrusaSlicer's names.
pub(crate) fn prusaslicer_ini(images: &LayerImages, r: &ResinSettings) -> String {
    let g = &images.grid;
    let orientation = if images.frame.portrait {
        "portrait"
    } else {
        "landscape"
    };
    [
        "printer_technology = SLA".to_string(),
        format!("printer_model = {}", r.printer_model),
        format!("printer_settings_id = {}", r.printer_model),
        format!("sla_material_settings_id = {}", r.material_name),
        format!("display_pixels_x = {}", g.width),
        format!("display_pixels_y = {}", g.height),
        format!("display_width = {}", g.width as f64 * g.pixel),
        format!("display_height = {}", g.height as f64 * g.pixel),
        format!("display_orientation = {orientation}"),
        format!("display_mirror_x = {}", u8::from(images.frame.mirror_x)),
        format!("display_mirror_y = {}", u8::from(images.frame.mirror_y)),
        format!("layer_height = {}", r.layer_height),
        format!("initial_layer_height = {}", r.first_layer_height),
        format!("exposure_time = {}", r.exposure_time),
        format!("initial_exposure_time = {}", r.first_exposure_time),
        format!("faded_layers = {}", r.faded_layers),
        format!("max_print_height = {}", r.max_height),
    ]
    .join("\n")
        + "\n"
}

fn zerr(e: impl std::fmt::Display) -> SliceError {
    SliceError::Encode {
        what: "SL1 archive",
        message: e.to_string(),
    }
}

/// Writes the archive. `job` names the layer images (`<job>00000.png`) and `jobDir`.
pub fn write_sl1<W: Write + Seek>(
    out: W,
    images: &LayerImages,
    r: &ResinSettings,
    job: &str,
    thumbnail: &[u8],
) -> Result<(), SliceError> {
    let mut zip = ZipWriter::new(out);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    // Layer PNGs are compressed already, but a layer's rows compress to runs that repeat, and
    // deflating them again takes the cube's archive from 3.7 MB to a few hundred kB
    // (docs/slicing.md); the thumbnail is stored as it is.
    let stored = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    zip.start_file("config.ini", deflate).map_err(zerr)?;
    zip.write_all(config_ini(images, r, job).as_bytes())
        .map_err(zerr)?;
    zip.start_file("prusaslicer.ini", deflate).map_err(zerr)?;
    zip.write_all(prusaslicer_ini(images, r).as_bytes())
        .map_err(zerr)?;
    for (k, png) in images.pngs.iter().enumerate() {
        zip.start_file(format!("{job}{k:05}.png"), deflate)
            .map_err(zerr)?;
        zip.write_all(png).map_err(zerr)?;
    }
    zip.start_file(
        format!("thumbnail/thumbnail{}x{}.png", THUMBNAIL.0, THUMBNAIL.1),
        stored,
    )
    .map_err(zerr)?;
    zip.write_all(thumbnail).map_err(zerr)?;
    zip.finish().map_err(zerr)?;
    Ok(())
}

/// A thumbnail: the model's silhouette seen from above (every layer's white pixels), fit
/// into `size` pixels with a dark background.
pub fn thumbnail(
    silhouette: &[u8],
    grid_w: u32,
    grid_h: u32,
    size: (u32, u32),
) -> Result<Vec<u8>, SliceError> {
    let (tw, th) = size;
    let mut img = vec![24u8; tw as usize * th as usize];
    // The silhouette's box, so the model fills the picture.
    let (mut c0, mut r0, mut c1, mut r1) = (u32::MAX, u32::MAX, 0u32, 0u32);
    for r in 0..grid_h {
        for c in 0..grid_w {
            if silhouette[(r * grid_w + c) as usize] > 0 {
                c0 = c0.min(c);
                c1 = c1.max(c);
                r0 = r0.min(r);
                r1 = r1.max(r);
            }
        }
    }
    if c0 <= c1 && r0 <= r1 {
        let (bw, bh) = ((c1 - c0 + 1) as f64, (r1 - r0 + 1) as f64);
        let scale = (tw as f64 * 0.9 / bw).min(th as f64 * 0.9 / bh);
        let (ox, oy) = (
            (tw as f64 - bw * scale) * 0.5,
            (th as f64 - bh * scale) * 0.5,
        );
        for y in 0..th {
            for x in 0..tw {
                let sc = ((x as f64 + 0.5 - ox) / scale).floor();
                let sr = ((y as f64 + 0.5 - oy) / scale).floor();
                if sc >= 0.0 && sr >= 0.0 && sc < bw && sr < bh {
                    let v = silhouette[((r0 + sr as u32) * grid_w + c0 + sc as u32) as usize];
                    img[(y * tw + x) as usize] = img[(y * tw + x) as usize].max(v);
                }
            }
        }
    }
    encode_png(&img, tw, th)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Profile;

    #[test]
    fn exposure_fades_from_first_to_normal() {
        let r = Profile::default_resin().resin().unwrap();
        assert_eq!(exposure(&r, 0), r.first_exposure_time);
        assert!(exposure(&r, 1) < r.first_exposure_time && exposure(&r, 1) > r.exposure_time);
        assert!(exposure(&r, 5) < exposure(&r, 4));
        assert_eq!(exposure(&r, r.faded_layers + 1), r.exposure_time);
    }
}
