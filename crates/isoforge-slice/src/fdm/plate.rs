//! The plate: every object sliced into layer outlines once, its copies arranged on the bed,
//! and the outlines of all of them merged layer by layer in bed coordinates.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::SliceError;
use crate::geom::{Contour, Point, bbox};
use crate::source::{Layer, Source, check_layer_count, layer_stack};

use super::Control;

/// Outline simplification tolerance, mm: well under a line width, and enough to keep
/// dense contours from slowing polygon offsetting (docs/constants.md).
pub const OUTLINE_TOLERANCE: f64 = 0.005;

/// One layer of one object: its outline and its steep outline points.
type SlicedLayer = (Vec<Contour>, Vec<Point>);

/// A row of the bed arrangement: the items with their x, the row's width and height.
type Shelf = (Vec<(usize, f64)>, f64, f64);

/// Free space kept between arranged objects, mm (PrusaSlicer's arrangement keeps about 6).
pub const ARRANGE_GAP: f64 = 6.0;

/// One object's layers, centred on the origin in x and y, its bottom at z = 0.
pub struct ObjectLayers {
    /// Its layers (`model_z` in the model's own coordinates).
    pub layers: Vec<Layer>,
    /// Outline contours per layer, centred.
    pub outlines: Vec<Vec<Contour>>,
    /// Points of each layer's outline where the surface faces down more steeply than the
    /// support angle, centred.
    pub steep: Vec<Vec<Point>>,
    /// Its footprint (all layers), centred: `(min, max)`.
    pub footprint: (Point, Point),
    /// The model-to-centred translation (x, y, z).
    pub shift: [f64; 3],
}

/// What slicing an object needs to know.
#[derive(Copy, Clone, Debug)]
pub struct LayerSpec {
    /// First layer height, mm.
    pub first: f64,
    /// Layer height, mm.
    pub height: f64,
    /// Finest outline cell (fields), mm.
    pub cell: f64,
    /// −n_z beyond which a surface counts as steep (sin of the support angle).
    pub steep_below: f32,
}

/// Slices one object into layer outlines.
pub fn slice_object(
    source: &Source,
    spec: &LayerSpec,
    control: &Control,
    done: &AtomicUsize,
    total: usize,
) -> Result<ObjectLayers, SliceError> {
    let model = source.prepare(spec.cell, OUTLINE_TOLERANCE)?;
    check_layer_count(model.z_range.1 - model.z_range.0, spec.first, spec.height)?;
    let layers = layer_stack(model.z_range, spec.first, spec.height);
    let sliced: Vec<Result<SlicedLayer, SliceError>> = layers
        .par_iter()
        .map(|l| {
            if control.cancelled() {
                return Err(SliceError::Cancelled);
            }
            let (contours, tilts) = model.outline_with_tilts(
                l.model_z,
                (l.model_z - l.height * 0.5, l.model_z + l.height * 0.5),
            );
            let steep = contours
                .iter()
                .zip(&tilts)
                .flat_map(|(c, t)| {
                    c.iter()
                        .zip(t)
                        .filter(|(_, t)| **t > spec.steep_below)
                        .map(|(p, _)| *p)
                })
                .collect();
            control.progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            Ok((contours, steep))
        })
        .collect();
    let mut outlines = Vec::with_capacity(layers.len());
    let mut steep = Vec::with_capacity(layers.len());
    for r in sliced {
        let (c, s) = r?;
        outlines.push(c);
        steep.push(s);
    }
    let (lo, hi) = bbox(outlines.iter().flatten().flatten()).ok_or(SliceError::NoLayers)?;
    let centre = [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5];
    for p in outlines
        .iter_mut()
        .flatten()
        .flatten()
        .chain(steep.iter_mut().flatten())
    {
        p[0] -= centre[0];
        p[1] -= centre[1];
    }
    Ok(ObjectLayers {
        layers,
        outlines,
        steep,
        footprint: (
            [lo[0] - centre[0], lo[1] - centre[1]],
            [hi[0] - centre[0], hi[1] - centre[1]],
        ),
        shift: [-centre[0], -centre[1], -model.z_range.0],
    })
}

/// One copy of one object on the bed.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placement {
    /// Which object.
    pub object: usize,
    /// Where its centre goes on the bed.
    pub at: Point,
}

/// Arranges `copies` of each object on a bed of `bed` mm: rows of objects `gap` apart,
/// tallest footprints first, the whole arrangement centred on the bed. `margin` is kept
/// around each footprint (skirt, brim). A single object goes to the bed's centre.
pub fn arrange(
    objects: &[ObjectLayers],
    copies: usize,
    bed: [f64; 2],
    gap: f64,
    margin: f64,
) -> Result<Vec<Placement>, SliceError> {
    let size = |o: &ObjectLayers| {
        [
            o.footprint.1[0] - o.footprint.0[0],
            o.footprint.1[1] - o.footprint.0[1],
        ]
    };
    let mut items: Vec<usize> = (0..objects.len())
        .flat_map(|o| std::iter::repeat_n(o, copies.max(1)))
        .collect();
    items.sort_by(|&a, &b| size(&objects[b])[1].total_cmp(&size(&objects[a])[1]));
    // Shelf packing: fill a row left to right, then start the next one above it.
    let usable = bed[0] - 2.0 * margin;
    let mut rows: Vec<Shelf> = Vec::new();
    for &o in &items {
        let [w, h] = size(&objects[o]);
        match rows.last_mut() {
            Some((row, width, height)) if *width + gap + w <= usable => {
                row.push((o, *width + gap));
                *width += gap + w;
                *height = height.max(h);
            }
            _ => rows.push((vec![(o, 0.0)], w, h)),
        }
    }
    let total_w = rows.iter().map(|r| r.1).fold(0.0, f64::max);
    let total_h: f64 =
        rows.iter().map(|r| r.2).sum::<f64>() + gap * rows.len().saturating_sub(1) as f64;
    if total_w + 2.0 * margin > bed[0] || total_h + 2.0 * margin > bed[1] {
        return Err(SliceError::LargerThanBed {
            size: [total_w, total_h],
            with_skirt: [total_w + 2.0 * margin, total_h + 2.0 * margin],
            bed,
        });
    }
    let x0 = (bed[0] - total_w) * 0.5;
    let mut y = (bed[1] - total_h) * 0.5;
    let mut out = Vec::with_capacity(items.len());
    for (row, _, height) in &rows {
        for &(o, x) in row {
            let (lo, hi) = objects[o].footprint;
            // The footprint's lower-left corner at (x0 + x, y); the centre follows.
            out.push(Placement {
                object: o,
                at: [x0 + x - lo[0], y - lo[1]],
            });
            let _ = hi;
        }
        y += height + gap;
    }
    Ok(out)
}

/// Every object's layers merged on the bed.
pub struct Plate {
    /// The layers (the tallest object's; `model_z` is the first object's).
    pub layers: Vec<Layer>,
    /// Outline contours per layer, bed coordinates (copies may touch: regions merge them).
    pub outlines: Vec<Vec<Contour>>,
    /// Steep outline points per layer, bed coordinates.
    pub steep: Vec<Vec<Point>>,
    /// The first object's model-to-bed translation.
    pub offset: [f64; 3],
}

/// Merges the placed copies' outlines layer by layer.
pub fn merge(objects: &[ObjectLayers], placements: Vec<Placement>) -> Plate {
    let tallest = objects
        .iter()
        .enumerate()
        .max_by_key(|(_, o)| o.layers.len())
        .map_or(0, |(i, _)| i);
    let layers = objects
        .get(tallest)
        .map(|o| o.layers.clone())
        .unwrap_or_default();
    let mut outlines = vec![Vec::new(); layers.len()];
    let mut steep = vec![Vec::new(); layers.len()];
    for pl in &placements {
        let o = &objects[pl.object];
        let shift = |p: &Point| [p[0] + pl.at[0], p[1] + pl.at[1]];
        for (k, cs) in o.outlines.iter().enumerate() {
            outlines[k].extend(cs.iter().map(|c| c.iter().map(shift).collect::<Contour>()));
            steep[k].extend(o.steep[k].iter().map(shift));
        }
    }
    let mut layers = layers;
    // Keep the first object's model heights, where it has layers.
    if let Some(first) = objects.first() {
        for (l, f) in layers.iter_mut().zip(&first.layers) {
            l.model_z = f.model_z;
        }
    }
    let offset = match (placements.iter().find(|p| p.object == 0), objects.first()) {
        (Some(p), Some(o)) => [o.shift[0] + p.at[0], o.shift[1] + p.at[1], o.shift[2]],
        _ => [0.0; 3],
    };
    Plate {
        layers,
        outlines,
        steep,
        offset,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(w: f64, h: f64) -> ObjectLayers {
        ObjectLayers {
            layers: Vec::new(),
            outlines: Vec::new(),
            steep: Vec::new(),
            footprint: ([-w / 2.0, -h / 2.0], [w / 2.0, h / 2.0]),
            shift: [0.0; 3],
        }
    }

    #[test]
    fn one_object_goes_to_the_centre() {
        let p = arrange(&[object(20.0, 10.0)], 1, [220.0, 220.0], 6.0, 3.0).unwrap();
        assert_eq!(
            p,
            vec![Placement {
                object: 0,
                at: [110.0, 110.0]
            }]
        );
    }

    #[test]
    fn copies_do_not_overlap_and_stay_on_the_bed() {
        let objs = [object(20.0, 20.0), object(30.0, 10.0)];
        let p = arrange(&objs, 4, [220.0, 220.0], 6.0, 3.0).unwrap();
        assert_eq!(p.len(), 8);
        let boxes: Vec<(Point, Point)> = p
            .iter()
            .map(|pl| {
                let (lo, hi) = objs[pl.object].footprint;
                (
                    [lo[0] + pl.at[0], lo[1] + pl.at[1]],
                    [hi[0] + pl.at[0], hi[1] + pl.at[1]],
                )
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0[0] >= 3.0 && a.0[1] >= 3.0 && a.1[0] <= 217.0 && a.1[1] <= 217.0);
            for b in &boxes[i + 1..] {
                let apart = a.1[0] + 6.0 - 1e-9 <= b.0[0]
                    || b.1[0] + 6.0 - 1e-9 <= a.0[0]
                    || a.1[1] + 6.0 - 1e-9 <= b.0[1]
                    || b.1[1] + 6.0 - 1e-9 <= a.0[1];
                assert!(apart, "{a:?} and {b:?} are closer than the gap");
            }
        }
    }

    #[test]
    fn too_many_copies_are_refused() {
        match arrange(&[object(50.0, 50.0)], 20, [220.0, 220.0], 6.0, 3.0) {
            Err(SliceError::LargerThanBed { size, .. }) => assert!(size[1] > 220.0),
            other => panic!("{other:?}"),
        }
    }
}
