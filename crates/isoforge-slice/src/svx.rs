//! SVX voxel archives (the Shapeways voxel format): `manifest.xml` describing the grid,
//! and one 8-bit DENSITY slice per layer, `density/slice%04d.png`, slices stacked along z.

use std::io::{Seek, Write};

use zip::ZipWriter;
use zip::write::SimpleFileOptions;

use crate::SliceError;
use crate::raster::LayerImages;

/// `manifest.xml` for these slices: voxel size and origin in metres.
pub(crate) fn manifest(images: &LayerImages, voxel_mm: f64, origin_mm: [f64; 3]) -> String {
    let g = &images.grid;
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<grid version="1.0" gridSizeX="{}" gridSizeY="{}" gridSizeZ="{}" voxelSize="{}" originX="{}" originY="{}" originZ="{}" slicesOrientation="Z" subvoxelBits="8">
    <channels>
        <channel type="DENSITY" bits="8" slices="density/slice%04d.png"/>
    </channels>
    <metadata>
        <entry key="creator" value="isoforge {}"/>
    </metadata>
</grid>
"#,
        g.width,
        g.height,
        images.layers.len(),
        voxel_mm / 1000.0,
        origin_mm[0] / 1000.0,
        origin_mm[1] / 1000.0,
        origin_mm[2] / 1000.0,
        env!("CARGO_PKG_VERSION"),
    )
}

fn zerr(e: impl std::fmt::Display) -> SliceError {
    SliceError::Encode {
        what: "SVX archive",
        message: e.to_string(),
    }
}

/// Writes the archive.
pub fn write_svx<W: Write + Seek>(
    out: W,
    images: &LayerImages,
    voxel_mm: f64,
    origin_mm: [f64; 3],
) -> Result<(), SliceError> {
    let mut zip = ZipWriter::new(out);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let stored = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    zip.start_file("manifest.xml", deflate).map_err(zerr)?;
    zip.write_all(manifest(images, voxel_mm, origin_mm).as_bytes())
        .map_err(zerr)?;
    for (k, png) in images.pngs.iter().enumerate() {
        zip.start_file(format!("density/slice{k:04}.png"), stored)
            .map_err(zerr)?;
        zip.write_all(png).map_err(zerr)?;
    }
    zip.finish().map_err(zerr)?;
    Ok(())
}
