//! G-code judged by the checker: layers and Z heights, extrusion inside the part grown by a
//! line width, extruded volume against the part's volume, bed limits, temperatures first.

mod common;

use common::{Known, cube, sphere, torus};
use isoforge_slice::check::{GcodeReport, parse};
use isoforge_slice::{FdmSettings, GcodeJob, Profile, SliceError, Source, slice_gcode};

fn settings(sets: &[&str]) -> FdmSettings {
    let mut p = Profile::default_fdm();
    for s in sets {
        p.set(s).unwrap();
    }
    p.fdm().unwrap()
}

fn slice(k: &Known, s: &FdmSettings) -> (GcodeJob, GcodeReport) {
    let job = slice_gcode(&Source::field(&k.shape, k.bounds), s, &|_, _| {}).unwrap();
    let report = parse(&job.gcode).unwrap();
    (job, report)
}

fn part(feature: &str) -> bool {
    feature != "SKIRT"
}

/// Everything the checker checks, for a solid of known section and volume.
fn check_all(k: &Known, s: &FdmSettings, expected_volume: f64) {
    let (job, r) = slice(k, s);
    let height = k.bounds.size()[2] - 2.0; // the fixtures' bounds have 1 mm of air around
    // Layer count and Z heights.
    let n = 1 + ((height - s.first_layer_height) / s.layer_height - 1e-6).ceil() as usize;
    assert_eq!(r.layers.len(), n);
    assert_eq!(job.stats.layers, n);
    for (i, (k_, z)) in r.layers.iter().enumerate() {
        assert_eq!(*k_, i);
        let want = s.first_layer_height + i as f64 * s.layer_height;
        assert!(
            (z.unwrap() - want).abs() < 1e-3,
            "layer {i}: ;Z:{z:?} vs {want}"
        );
    }
    for (layer, z) in &r.layer_print_z {
        assert!(
            (z - r.layers[*layer].1.unwrap()).abs() < 1e-3,
            "layer {layer} printed at {z}"
        );
    }
    // Every extrusion inside the part's outline grown by a line width.
    let bad = r.outside_part(0.2, s.line_width, part, |x, y, layer| {
        let l = &job.layers[layer];
        (k.section)(x - job.offset[0], y - job.offset[1], l.model_z)
    });
    assert!(
        bad.is_empty(),
        "{} extrusions outside the part, e.g. line {}",
        bad.len(),
        bad[0]
    );
    // Volume.
    let v = r.volume(s.filament_diameter, part);
    assert!(
        (v / expected_volume - 1.0).abs() < 0.05,
        "extruded {v:.1} mm³, expected {expected_volume:.1}"
    );
    // Bed.
    for a in 0..2 {
        assert!(
            r.min[a] >= 0.0 && r.max[a] <= s.bed_size[a],
            "axis {a}: {:?} {:?}",
            r.min,
            r.max
        );
    }
    assert!(r.max[2] <= s.max_height);
    // Temperatures before the first extrusion.
    assert_eq!(r.nozzle_before_first_extrusion, Some(s.nozzle_temperature));
    assert_eq!(r.bed_before_first_extrusion, Some(s.bed_temperature));
    assert!(r.waited_for_nozzle);
    // The header's filament matches what the moves push (all of it, skirt included).
    assert!((r.filament_mm - job.stats.filament_mm).abs() < 0.01 * job.stats.filament_mm.max(1.0));
}

#[test]
fn solid_sphere_cube_and_torus_extrude_their_volume() {
    let s = settings(&["infill_density=1"]);
    for k in [sphere(10.0), cube(20.0), torus(15.0, 5.0)] {
        check_all(&k, &s, k.volume);
    }
}

#[test]
fn sparse_cube_extrudes_shell_plus_density_times_core() {
    // A cube a wide: perimeters p of width w around, `bottom` and `top` solid layers; the
    // core in between is filled to the density.
    for pattern in ["rectilinear", "grid"] {
        let s = settings(&[
            "infill_density=0.2",
            &format!("infill_pattern={pattern}"),
            "perimeters=2",
            "top_layers=4",
            "bottom_layers=3",
        ]);
        let k = cube(20.0);
        let a = 20.0;
        let core_side = a - 2.0 * s.perimeters as f64 * s.line_width;
        let core_height = a - (s.top_layers + s.bottom_layers) as f64 * s.layer_height;
        let core = core_side * core_side * core_height;
        let expected = a * a * a - core * (1.0 - s.infill_density);
        check_all(&k, &s, expected);
    }
}

#[test]
fn gyroid_infill_stays_inside_and_prints() {
    let s = settings(&["infill_pattern=gyroid", "infill_density=0.15"]);
    let k = torus(15.0, 5.0);
    let (job, r) = slice(&k, &s);
    assert!(r.extrusions.iter().any(|x| x.feature == "FILL"));
    let bad = r.outside_part(0.2, s.line_width, part, |x, y, layer| {
        (k.section)(
            x - job.offset[0],
            y - job.offset[1],
            job.layers[layer].model_z,
        )
    });
    assert!(bad.is_empty());
}

#[test]
fn skirt_fan_retraction_and_progress_are_there() {
    let s = settings(&[]);
    let (job, r) = slice(&sphere(8.0), &s);
    let skirt: Vec<_> = r
        .extrusions
        .iter()
        .filter(|x| x.feature == "SKIRT")
        .collect();
    assert!(!skirt.is_empty() && skirt.iter().all(|x| x.layer == Some(0)));
    let g = &job.gcode;
    let fan = g.find("M106").unwrap();
    assert!(fan > g.find(";LAYER:1\n").unwrap() && fan < g.find(";LAYER:2\n").unwrap());
    assert!(g.contains(&format!("G1 E-{:.5}", s.retract_length)) || g.contains("E-"));
    assert_eq!(g.matches("M73 P").count(), job.stats.layers + 1);
    assert!(g.contains("; filament used [g] =") && g.contains("; estimated printing time"));
    // The outer wall comes after the inner one on each layer (near the bottom of the
    // sphere the outer wall leans past the support angle: an overhang).
    for layer in [5, 40] {
        let here: Vec<&str> = r
            .extrusions
            .iter()
            .filter(|x| x.layer == Some(layer))
            .map(|x| x.feature.as_str())
            .collect();
        let last_inner = here.iter().rposition(|f| *f == "WALL-INNER").unwrap();
        let first_outer = here
            .iter()
            .position(|f| *f == "WALL-OUTER" || *f == "OVERHANG")
            .unwrap();
        assert!(first_outer > last_inner, "layer {layer}: {here:?}");
    }
    let at = |layer: usize, f: &str| {
        r.extrusions
            .iter()
            .any(|x| x.layer == Some(layer) && x.feature == f)
    };
    assert!(at(5, "OVERHANG") && !at(40, "OVERHANG"));
}

#[test]
fn a_model_larger_than_the_bed_is_refused() {
    let s = settings(&["bed_size=15,15"]);
    let k = sphere(10.0);
    match slice_gcode(&Source::field(&k.shape, k.bounds), &s, &|_, _| {}) {
        Err(SliceError::LargerThanBed { size, bed, .. }) => {
            assert_eq!(bed, [15.0, 15.0]);
            assert!(size[0] > 19.0 && size[1] > 19.0, "{size:?}");
        }
        other => panic!("expected a size error, got {:?}", other.map(|j| j.stats)),
    }
}
