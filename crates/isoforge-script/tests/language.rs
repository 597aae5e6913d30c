//! The scripting language of docs/language.md ("The language core").

use std::path::Path;

use isoforge_field::{PointEval, Shape, Tape};
use isoforge_script::{Model, ScriptError, load_script};

fn load(src: &str) -> Result<Model, ScriptError> {
    load_script(Path::new("test.rhai"), src, &[])
}

fn shape(src: &str) -> Shape {
    match load(src) {
        Ok(m) => m.shape,
        Err(e) => panic!("script failed: {e}\n{src}"),
    }
}

fn at(s: &Shape, p: [f64; 3]) -> f64 {
    PointEval::new().eval(&Tape::new(s), p)
}

/// Runs `checks` (statements that `throw` on failure), then returns a shape.
fn check(checks: &str) {
    let src = format!("{checks}\nSphere(1)");
    if let Err(e) = load(&src) {
        panic!("{e}");
    }
}

#[test]
fn integer_division_is_real() {
    check(r#"if 9/4 != 2.25 { throw "9/4 = " + (9/4) }"#);
    check(r#"if 9/80 != 0.1125 { throw "9/80 = " + (9/80) }"#);
    check(r#"if 1/2 + 1/2 != 1.0 { throw "halves" }"#);
}

#[test]
fn caret_is_power() {
    check(r#"if 2^3 != 8 { throw "2^3 = " + (2^3) }"#);
    check(r#"if 2.0^0.5 != sqrt(2.0) { throw "2.0^0.5" }"#);
    check(r#"if 2^-1 != 0.5 { throw "2^-1 = " + (2^-1) }"#);
    check(r#"if 4^0.5 != 2.0 { throw "4^0.5" }"#);
    let s = shape("(x^2 + y^2)^0.5 - 1");
    assert!((at(&s, [3.0, 4.0, 0.0]) - 4.0).abs() < 1e-12);
}

#[test]
fn coordinates_work_inside_functions() {
    let s = shape("fn Ball(a) { x^2 + y^2 + z^2 - a^2 }\nBall(2)");
    assert_eq!(at(&s, [0.0, 0.0, 0.0]), -4.0);
    assert_eq!(at(&s, [2.0, 0.0, 0.0]), 0.0);
    // A user function may even shadow a library name, as the issue's example does.
    let s = shape("fn Sphere(a) { x^2 + y^2 + z^2 - a^2 }\nSphere(3)");
    assert_eq!(at(&s, [0.0, 0.0, 1.0]), -8.0);
}

#[test]
fn own_variables_named_like_coordinates_win() {
    let s = shape("fn f(x) { x * 2 }\nlet y = 5;\nSphere(1) + f(3) + y");
    assert_eq!(at(&s, [0.0, 0.0, 0.0]), -1.0 + 6.0 + 5.0);
}

#[test]
fn constants() {
    check(r#"if PI != 3.141592653589793 { throw "PI" }"#);
    check(r#"if E != 2.718281828459045 { throw "E" }"#);
    check(r#"if DegToRad(180) != PI { throw "DegToRad" }"#);
    let s = shape("fn f() { PI * x }\nf()");
    assert_eq!(at(&s, [2.0, 0.0, 0.0]), 2.0 * std::f64::consts::PI);
}

#[test]
fn shapes_and_numbers_mix_in_either_order() {
    let s = shape(
        "2 * x + x / 2 + (1 - x) + (x - 1) + 0.5 * y + y * 0.5 + (3.0 + z) + (z + 3) - x*y/z",
    );
    let (x, y, z) = (1.5, -2.0, 0.5);
    let want = 2.0 * x + x / 2.0 + (1.0 - x) + (x - 1.0) + y + (3.0 + z) + (z + 3.0) - x * y / z;
    assert!((at(&s, [x, y, z]) - want).abs() < 1e-12);
    let s = shape("-x + -(y * 2)");
    assert_eq!(at(&s, [1.0, 2.0, 0.0]), -5.0);
    let s = shape("5 * Sphere(1)");
    assert_eq!(at(&s, [0.0, 0.0, 0.0]), -5.0);
}

#[test]
fn math_on_numbers_gives_numbers_and_on_shapes_shapes() {
    check(r#"if type_of(sin(2.0)) != "f64" { throw type_of(sin(2.0)) }"#);
    check(r#"if sin(2) != sin(2.0) { throw "sin int" }"#);
    check(r#"if type_of(sin(x)) != "Shape" { throw type_of(sin(x)) }"#);
    check(r#"if min(2, 3.5) != 2.0 || max(2, 3.5) != 3.5 { throw "min/max" }"#);
    check(r#"if square(3) != 9.0 || floor(2.7) != 2.0 || abs(-2.5) != 2.5 { throw "sq" }"#);
    check(r#"if pow(2, 10) != 1024.0 || atan2(1, 1) != PI / 4 { throw "pow/atan2" }"#);
    check(r#"if exp(0) != 1.0 || ln(E) != 1.0 || sqrt(16) != 4.0 { throw "exp/ln" }"#);
    check(
        r#"if tan(0) != 0.0 || asin(1) != PI/2 || acos(1) != 0.0 || atan(0) != 0.0 { throw "trig" }"#,
    );
    let p = [0.3, -0.6, 0.2];
    let cases: [(&str, f64); 16] = [
        ("sin(x)", 0.3f64.sin()),
        ("cos(x)", 0.3f64.cos()),
        ("tan(x)", 0.3f64.tan()),
        ("asin(y)", (-0.6f64).asin()),
        ("acos(y)", (-0.6f64).acos()),
        ("atan(y)", (-0.6f64).atan()),
        ("atan2(y, x)", (-0.6f64).atan2(0.3)),
        ("exp(z)", 0.2f64.exp()),
        ("ln(x)", 0.3f64.ln()),
        ("sqrt(x)", 0.3f64.sqrt()),
        ("abs(y)", 0.6),
        ("min(x, y)", -0.6),
        ("max(x, 0.5)", 0.5),
        ("square(y)", 0.36),
        ("floor(y)", -1.0),
        ("pow(x, z)", 0.3f64.powf(0.2)),
    ];
    for (src, want) in cases {
        let got = at(&shape(src), p);
        assert!((got - want).abs() < 1e-12, "{src}: {got} != {want}");
    }
    let got = at(&shape("DegToRad(x)"), [90.0, 0.0, 0.0]);
    assert!((got - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
}

#[test]
fn every_classic_name_is_callable() {
    let names = [
        "Sphere(1)",
        "Cube(1)",
        "Prism(1, 2, 3)",
        "Torus(2, 0.5)",
        "Cyl(1, 1, 2)",
        "Cyyl(1, 1, 2)",
        "Cone(1, 1, 2)",
        "Ellip(1, 2, 3)",
        "Para(1, 1, 1)",
        "Close(z, 2)",
        "HSpace(1)",
        "Tetrahedral(18, 18, 60)",
        "Sinus(0, 5)",
        "Bug(-0.5, 1, 4)",
        "Drope(4)",
        "Heart(1, 9/4, 1, 1, 9/80)",
        "TransX(Sphere(1), 1)",
        "TransY(Sphere(1), 1)",
        "TransZ(Sphere(1), 1)",
        "ScaleX(Sphere(1), 2)",
        "ScaleY(Sphere(1), 2)",
        "ScaleZ(Sphere(1), 2)",
        "ScaleXYZ(Sphere(1), 2)",
        "ReflectXY(Sphere(1))",
        "ReflectZX(Sphere(1))",
        "ReflectYZ(Sphere(1))",
        "RotateRX(Cube(1), PI/4)",
        "RotateRY(Cube(1), PI/4)",
        "RotateRZ(Cube(1), PI/4)",
        "RotateX(Cube(1), 45)",
        "RotateY(Cube(1), 45)",
        "RotateZ(Cube(1), 45)",
        "Union(Sphere(1), Cube(1))",
        "Intersect(Sphere(1), Cube(1))",
        "Subtract(Sphere(1), Cube(1))",
        "Morph(Sphere(1), Cube(1), 0.5)",
        "Blend(Sphere(1), Cube(1), 0.5)",
        "Combine(Sphere(1), Cube(1), 2)",
        "Max(Sphere(1), Cube(1))",
        "Min(Sphere(1), Cube(1))",
        "curve_fol_sphere(|t| [t, 0, 0], 3, [0, 1], 0.5)",
        "curve_fol_cyl(|t| [t, t*t, t], 3, [0, 1], [1, 1, 1])",
        "curve_fol_cyyl(|t| [t, t*t, t], 3, [0, 1], [1, 1, 1])",
        "curve_fol_box(|t| [t, 0, 0], 3, [0, 1], 0.5)",
    ];
    for src in names {
        let s = shape(src);
        assert!(at(&s, [0.0, 0.0, 0.0]).is_finite(), "{src}");
    }
}

#[test]
fn classic_calls_match_the_library() {
    let p = [0.3, -0.2, 0.4];
    let s = shape("Heart(1, 9/4, 1, 1, 9/80)");
    let l = isoforge_shapes::classic::heart(1.0, 2.25, 1.0, 1.0, 0.1125);
    assert_eq!(at(&s, p), at(&l, p));
    let s = shape("RotateY(TransZ(Drope(4), 2.5), 90)");
    let l = isoforge_shapes::classic::rotate_y(
        &isoforge_shapes::classic::trans_z(&isoforge_shapes::classic::drope(4.0), 2.5),
        90.0,
    );
    assert_eq!(at(&s, p), at(&l, p));
}

#[test]
fn params_default_and_override() {
    let src = "let r = param(\"r\", 2, 1, 5);\nlet n = param(\"n\", 7);\nSphere(r) + n";
    let m = load(src).unwrap();
    assert_eq!(m.params.len(), 2);
    assert_eq!(m.params[0].name, "r");
    assert_eq!(m.params[0].value, 2.0);
    assert_eq!(m.params[0].range, Some((1.0, 5.0)));
    assert_eq!(at(&m.shape, [0.0, 0.0, 0.0]), -4.0 + 7.0);
    let m = load_script(Path::new("p.rhai"), src, &[("r".into(), 3.0)]).unwrap();
    assert_eq!(m.params[0].value, 3.0);
    assert_eq!(m.params[0].default, 2.0);
    assert_eq!(at(&m.shape, [0.0, 0.0, 0.0]), -9.0 + 7.0);
    // An integer parameter stays an integer, so it can count copies.
    let m = load("curve_fol_sphere(|t| [t, 0, 0], param(\"n\", 4), [0, 4], 0.25)").unwrap();
    assert!(at(&m.shape, [3.0, 0.0, 0.0]) < 0.0);
}

#[test]
fn bounds_are_recorded() {
    let m = load("bounds([-1, -2, -3], [1, 2.5, 3]);\nSphere(1)").unwrap();
    let b = m.bounds.unwrap();
    assert_eq!(b.min, [-1.0, -2.0, -3.0]);
    assert_eq!(b.max, [1.0, 2.5, 3.0]);
    assert!(load("Sphere(1)").unwrap().bounds.is_none());
}

#[test]
fn closures_capture_and_run_only_at_build_time() {
    let s = shape("let r = 4;\ncurve_fol_sphere(|t| [r*sin(t), r*cos(t), 0], 7, [0, 2*PI], 2)");
    assert!(at(&s, [0.0, 4.0, 0.0]) < 0.0);
    assert!(at(&s, [0.0, 0.0, 0.0]) > 0.0);
}

#[test]
fn print_goes_to_stderr_and_the_script_still_runs() {
    let s = shape("print(\"hello\");\nSphere(1)");
    assert_eq!(at(&s, [0.0, 0.0, 0.0]), -1.0);
}

#[test]
fn caret_binds_as_in_math() {
    check(r#"if 2^3^2 != 512 { throw "2^3^2 = " + (2^3^2) }"#);
    check(r#"if -2^2 != -4 { throw "-2^2 = " + (-2^2) }"#);
    check(r#"if 2*3^2 != 18 { throw "2*3^2" }"#);
    check(r#"let a = 3; a ^= 2; if a != 9 { throw "a ^= 2 gives " + a }"#);
    let s = shape("exp(-x^2 - y^2)");
    assert!((at(&s, [1.0, 1.0, 0.0]) - (-2.0f64).exp()).abs() < 1e-12);
    let s = shape("z - 4*x*exp(-x^2-y^2)");
    let l = isoforge_shapes::classic::drope(4.0);
    assert_eq!(at(&s, [0.5, 0.2, 0.1]), at(&l, [0.5, 0.2, 0.1]));
    let s = shape("1 / -x^2");
    assert_eq!(at(&s, [2.0, 0.0, 0.0]), -0.25);
}
