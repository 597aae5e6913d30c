//! Every name of the modern library (SCRIPT_API.md's "The modern library", docs/library-modern.md)
//! exists, is called as the contract writes it, and does what it says at a few points: exact
//! distances where a primitive is exact, the right side of the surface elsewhere. `import_stl`
//! is tested with its files in tests/import.rs, the exact volumes in tests/modern_volumes.rs.

use std::path::Path;

use isoforge_field::{PointEval, Shape, Tape};
use isoforge_script::load_script;

fn shape(src: &str) -> Shape {
    match load_script(Path::new("names.rhai"), src, &[]) {
        Ok(m) => m.shape,
        Err(e) => panic!("script failed: {e}\n{src}"),
    }
}

fn at(s: &Shape, p: [f64; 3]) -> f64 {
    PointEval::new().eval(&Tape::new(s), p)
}

/// A call and what it must give: exact values at points, then points inside and outside.
struct Case {
    src: &'static str,
    exact: &'static [([f64; 3], f64)],
    inside: &'static [[f64; 3]],
    outside: &'static [[f64; 3]],
}

const CASES: &[Case] = &[
    // Primitives, exact signed distances.
    Case {
        src: "sphere(2)",
        exact: &[
            ([0.0, 0.0, 0.0], -2.0),
            ([3.0, 0.0, 0.0], 1.0),
            ([0.0, 4.0, 0.0], 2.0),
        ],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "box([2, 4, 6])",
        exact: &[
            ([0.0, 0.0, 0.0], -1.0),
            ([2.0, 0.0, 0.0], 1.0),
            ([0.0, 0.0, -4.0], 1.0),
        ],
        inside: &[[0.9, 1.9, 2.9], [-0.9, -1.9, -2.9]],
        outside: &[[1.1, 0.0, 0.0], [0.0, 2.1, 0.0]],
    },
    Case {
        src: "cylinder(1, 4)",
        exact: &[
            ([0.0, 0.0, 2.5], 0.5),
            ([2.0, 0.0, 0.0], 1.0),
            ([0.0, 0.0, -2.5], 0.5),
        ],
        inside: &[[0.0, 0.0, 1.9], [0.0, 0.9, -1.9]],
        outside: &[[0.8, 0.8, 0.0]],
    },
    Case {
        src: "cone(1, 2)",
        exact: &[([0.0, 0.0, -0.5], 0.5), ([0.0, 0.0, 2.5], 0.5)],
        inside: &[[0.0, 0.0, 0.1], [0.8, 0.0, 0.1], [0.0, 0.0, 1.9]],
        outside: &[[0.6, 0.0, 1.0], [1.1, 0.0, 0.05]],
    },
    Case {
        src: "torus(3, 1)",
        exact: &[
            ([3.0, 0.0, 0.0], -1.0),
            ([0.0, 0.0, 0.0], 2.0),
            ([0.0, 3.0, 2.0], 1.0),
        ],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "ellipsoid([1, 2, 3])",
        exact: &[],
        inside: &[[0.0, 0.0, 2.9], [0.0, 1.9, 0.0], [0.9, 0.0, 0.0]],
        outside: &[
            [0.0, 0.0, 3.1],
            [0.0, 2.1, 0.0],
            [1.1, 0.0, 0.0],
            [0.6, 1.2, 1.8],
        ],
    },
    Case {
        src: "capsule([0, 0, 0], [0, 0, 4], 1)",
        exact: &[
            ([0.0, 0.0, 2.0], -1.0),
            ([2.0, 0.0, 2.0], 1.0),
            ([0.0, 0.0, 5.5], 0.5),
        ],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "half_space([0, 0, 1], 2)",
        exact: &[([0.0, 0.0, 3.0], 1.0), ([5.0, -7.0, 0.0], -2.0)],
        inside: &[],
        outside: &[],
    },
    Case {
        // A sheet round the gyroid surface sin x cos y + sin y cos z + sin z cos x = 0
        // (period 2π mm here), which passes through the origin.
        src: "gyroid(2 * PI, 0.5)",
        exact: &[],
        inside: &[[0.0, 0.0, 0.0], [PI_F, 0.0, 0.0]],
        outside: &[[PI_F / 2.0, 0.0, 0.0]],
    },
    // Transforms, as functions and as methods.
    Case {
        src: "move(sphere(1), [5, 0, 0])",
        exact: &[([5.0, 0.0, 0.0], -1.0), ([0.0, 0.0, 0.0], 4.0)],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "sphere(1).move([0, 5, 0])",
        exact: &[([0.0, 5.0, 0.0], -1.0), ([0.0, 7.0, 0.0], 1.0)],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "scale(sphere(1), 2)",
        exact: &[([1.5, 0.0, 0.0], -0.5), ([0.0, 0.0, 3.0], 1.0)],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "sphere(1).scale([1, 1, 3])",
        exact: &[],
        inside: &[[0.0, 0.0, 2.9]],
        outside: &[[0.0, 1.1, 0.0], [0.0, 0.0, 3.1]],
    },
    Case {
        src: "rotate_x(box([1, 1, 4]), 90)",
        exact: &[([0.0, 0.0, 0.0], -0.5)],
        inside: &[[0.0, 1.9, 0.0]],
        outside: &[[0.0, 0.0, 1.9]],
    },
    Case {
        src: "box([1, 1, 4]).rotate_y(90)",
        exact: &[],
        inside: &[[1.9, 0.0, 0.0]],
        outside: &[[0.0, 0.0, 1.9]],
    },
    Case {
        src: "rotate_z(box([4, 1, 1]), 90)",
        exact: &[],
        inside: &[[0.0, 1.9, 0.0]],
        outside: &[[1.9, 0.0, 0.0]],
    },
    Case {
        src: "rotate(box([1, 1, 4]), [1, 0, 0], 90)",
        exact: &[([0.0, 3.0, 0.0], 1.0)],
        inside: &[[0.0, -1.9, 0.0]],
        outside: &[[0.0, 0.0, -1.9]],
    },
    Case {
        src: "mirror_x(sphere(1).move([2, 0, 0]))",
        exact: &[([-2.0, 0.0, 0.0], -1.0)],
        inside: &[],
        outside: &[[2.0, 0.0, 0.0]],
    },
    Case {
        src: "sphere(1).move([0, 2, 0]).mirror_y()",
        exact: &[([0.0, -2.0, 0.0], -1.0)],
        inside: &[],
        outside: &[[0.0, 2.0, 0.0]],
    },
    Case {
        src: "mirror_z(sphere(1).move([0, 0, 2]))",
        exact: &[([0.0, 0.0, -2.0], -1.0)],
        inside: &[],
        outside: &[[0.0, 0.0, 2.0]],
    },
    Case {
        // 9°/mm: the bar's long side along x at z = 0 has turned to y at z = ±10.
        src: "twist(box([4, 1, 20]), 9)",
        exact: &[],
        inside: &[[1.8, 0.0, 0.0], [0.0, 1.8, 9.9], [0.0, 1.8, -9.9]],
        outside: &[[0.0, 1.8, 0.0], [1.8, 0.0, 9.9]],
    },
    // Booleans and blends.
    Case {
        src: "union(sphere(1), sphere(1).move([3, 0, 0]))",
        exact: &[
            ([0.0, 0.0, 0.0], -1.0),
            ([3.0, 0.0, 0.0], -1.0),
            ([1.5, 0.0, 0.0], 0.5),
        ],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "union([sphere(1), sphere(1).move([3, 0, 0]), sphere(1).move([6, 0, 0])])",
        exact: &[([6.0, 0.0, 0.0], -1.0), ([4.5, 0.0, 0.0], 0.5)],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "intersection(sphere(2), box([2, 2, 2]))",
        exact: &[([0.0, 0.0, 0.0], -1.0)],
        inside: &[[0.9, 0.9, 0.9]],
        outside: &[[1.5, 0.0, 0.0]],
    },
    Case {
        src: "intersection([sphere(2), box([2, 2, 2]), half_space([0, 0, 1], 0)])",
        exact: &[],
        inside: &[[0.5, 0.5, -0.5]],
        outside: &[[0.5, 0.5, 0.5], [1.5, 0.0, -0.5]],
    },
    Case {
        src: "difference(box([4, 4, 4]), sphere(1))",
        exact: &[([0.0, 0.0, 0.0], 1.0)],
        inside: &[[1.5, 1.5, 1.5]],
        outside: &[[0.5, 0.0, 0.0]],
    },
    Case {
        src: "difference([box([4, 4, 4]), sphere(1), sphere(1).move([2, 2, 2])])",
        exact: &[],
        inside: &[[1.5, -1.5, 1.5]],
        outside: &[[0.5, 0.0, 0.0], [1.8, 1.8, 1.8]],
    },
    Case {
        // Two balls 0.2 apart: a plain union leaves the gap empty, the blend fills it.
        src: "smooth_union(sphere(1).move([-1.1, 0, 0]), sphere(1).move([1.1, 0, 0]), 1)",
        exact: &[],
        inside: &[[0.0, 0.0, 0.0]],
        outside: &[[0.0, 0.0, 1.0], [2.2, 0.0, 0.0]],
    },
    Case {
        // The blend rounds the lens's rim inward: just inside the sharp rim is outside.
        src: "smooth_intersection(sphere(1).move([-0.5, 0, 0]), sphere(1).move([0.5, 0, 0]), 0.5)",
        exact: &[],
        inside: &[[0.0, 0.0, 0.0]],
        outside: &[[0.0, 0.0, 0.85], [0.0, 0.0, 1.0]],
    },
    Case {
        // A dimple in the top face, its rim rounded: just beside the sharp rim is outside.
        src: "smooth_difference(box([4, 4, 4]), sphere(1).move([0, 0, 2]), 0.5)",
        exact: &[],
        inside: &[[1.5, 0.0, 1.9], [0.0, 0.0, 0.9]],
        outside: &[[0.0, 0.0, 1.5], [1.0, 0.0, 1.98]],
    },
    Case {
        src: "offset(sphere(1), 0.5)",
        exact: &[([0.0, 0.0, 0.0], -1.5), ([2.0, 0.0, 0.0], 0.5)],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "offset(box([2, 2, 2]), -0.25)",
        exact: &[([0.0, 0.0, 0.0], -0.75)],
        inside: &[[0.7, 0.7, 0.7]],
        outside: &[[0.8, 0.0, 0.0]],
    },
    Case {
        // Not a distance field: the gradient makes the offset 0.1 apart either way.
        src: "offset(Sphere(1), 0.1)",
        exact: &[],
        inside: &[[1.05, 0.0, 0.0]],
        outside: &[[1.15, 0.0, 0.0]],
    },
    Case {
        src: "shell(sphere(10), 1)",
        exact: &[([9.5, 0.0, 0.0], -0.5), ([11.0, 0.0, 0.0], 1.0)],
        inside: &[[0.0, -9.1, 0.0]],
        outside: &[[0.0, 0.0, 0.0], [8.9, 0.0, 0.0]],
    },
    Case {
        src: "shell(Heart(1, 9/4, 1, 1, 9/80), 0.1)",
        exact: &[],
        inside: &[],
        outside: &[[0.0, 0.0, 0.0]],
    },
    // Function volumes.
    Case {
        src: "bounds([-5, -5, -5], [5, 5, 5]); cartesian(|x, y| 2 + 0.1 * x, 0)",
        exact: &[],
        inside: &[[0.0, 0.0, 1.9], [0.0, 0.0, -4.5], [3.0, 0.0, 2.2]],
        outside: &[[0.0, 0.0, 2.1], [-3.0, 0.0, 1.8]],
    },
    Case {
        src: "bounds([-5, -5, -5], [5, 5, 5]); cartesian(|x, y| 0, 1)",
        exact: &[],
        inside: &[[0.0, 0.0, -0.5], [4.0, -4.0, -0.9]],
        outside: &[[0.0, 0.0, 0.1], [0.0, 0.0, -1.1]],
    },
    Case {
        src: "spherical(|theta, phi| 5, [1, 0, 0])",
        exact: &[],
        inside: &[[5.9, 0.0, 0.0], [1.0, 0.0, 4.9], [-3.9, 0.0, 0.0]],
        outside: &[[6.1, 0.0, 0.0], [1.0, 0.0, 5.1]],
    },
    Case {
        // r(θ) = 4 + cos θ: 5 along +x, 3 along −x.
        src: "spherical(|theta, phi| 4 + cos(theta), [0, 0, 0])",
        exact: &[],
        inside: &[[4.9, 0.0, 0.0], [-2.9, 0.0, 0.0]],
        outside: &[[5.1, 0.0, 0.0], [-3.1, 0.0, 0.0]],
    },
    Case {
        src: "spherical(|theta, phi| 5, [0, 0, 0], #{thickness: 1})",
        exact: &[],
        inside: &[[4.5, 0.0, 0.0]],
        outside: &[[0.0, 0.0, 0.0], [3.9, 0.0, 0.0], [5.1, 0.0, 0.0]],
    },
    Case {
        src: "curve_tube(|s| [10 * cos(s), 10 * sin(s), 0], |s, theta| 2, 0, 2 * PI)",
        exact: &[],
        inside: &[[10.0, 0.0, 0.0], [0.0, -11.9, 0.0], [-10.0, 0.0, 1.9]],
        outside: &[[0.0, 0.0, 0.0], [12.1, 0.0, 0.0], [0.0, 10.0, 2.1]],
    },
    Case {
        // An open segment with a radius growing along it, flat caps at the ends.
        src: "curve_tube(|s| [s, 0, 0], |s, theta| 1 + s / 10, 0, 10)",
        exact: &[],
        inside: &[[0.1, 0.0, 0.9], [9.9, 0.0, 1.9]],
        outside: &[[0.0, 0.0, 1.2], [10.1, 0.0, 0.0], [-0.1, 0.0, 0.0]],
    },
    // Metaballs, hull.
    Case {
        src: "metaballs([[0, 0, 0, 2]], 1)",
        exact: &[],
        inside: &[[1.95, 0.0, 0.0]],
        outside: &[[2.05, 0.0, 0.0]],
    },
    Case {
        src: "metaballs([[0, 0, 0, 2], [10, 0, 0, 1]], 1, #{falloff: \"wyvill\"})",
        exact: &[],
        inside: &[[0.0, 1.95, 0.0], [10.0, 0.0, 0.95]],
        outside: &[[0.0, 2.05, 0.0], [5.0, 0.0, 0.0]],
    },
    Case {
        src: "hull([sphere(1), sphere(1).move([10, 0, 0])])",
        exact: &[
            ([5.0, 0.0, 0.0], -1.0),
            ([5.0, 0.0, 2.0], 1.0),
            ([12.0, 0.0, 0.0], 1.0),
        ],
        inside: &[],
        outside: &[],
    },
    Case {
        src: "hull([box([2, 2, 2]), box([2, 2, 2]).move([0, 0, 10])])",
        exact: &[([0.0, 0.0, 5.0], -1.0), ([2.0, 0.0, 5.0], 1.0)],
        inside: &[],
        outside: &[],
    },
];

const PI_F: f64 = std::f64::consts::PI;

#[test]
fn every_modern_name_does_what_the_contract_says() {
    let mut failures = Vec::new();
    for case in CASES {
        let s = shape(case.src);
        for &(p, want) in case.exact {
            let got = at(&s, p);
            if (got - want).abs() > 1e-6 {
                failures.push(format!("{}: at {p:?} {got}, want {want}", case.src));
            }
        }
        for &p in case.inside {
            let got = at(&s, p);
            if got.is_nan() || got >= 0.0 {
                failures.push(format!("{}: {p:?} should be inside, field {got}", case.src));
            }
        }
        for &p in case.outside {
            let got = at(&s, p);
            if got.is_nan() || got <= 0.0 {
                failures.push(format!(
                    "{}: {p:?} should be outside, field {got}",
                    case.src
                ));
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// The names of the modern library in SCRIPT_API.md, each of which a case above calls.
const NAMES: &[&str] = &[
    "sphere",
    "box",
    "cylinder",
    "cone",
    "torus",
    "ellipsoid",
    "capsule",
    "half_space",
    "gyroid",
    "move",
    "scale",
    "rotate_x",
    "rotate_y",
    "rotate_z",
    "rotate",
    "mirror_x",
    "mirror_y",
    "mirror_z",
    "twist",
    "union",
    "intersection",
    "difference",
    "smooth_union",
    "smooth_intersection",
    "smooth_difference",
    "offset",
    "shell",
    "cartesian",
    "spherical",
    "curve_tube",
    "metaballs",
    "hull",
];

#[test]
fn every_name_of_the_contract_has_a_case() {
    for name in NAMES {
        let called = CASES
            .iter()
            .any(|c| c.src.contains(&format!("{name}(")) || c.src.contains(&format!(".{name}(")));
        assert!(called, "{name} has no case");
    }
}

#[test]
fn an_unknown_option_is_an_error_naming_it() {
    for (src, key) in [
        (
            "metaballs([[0, 0, 0, 1]], 1, #{falof: \"wyvill\"})",
            "falof",
        ),
        ("spherical(|t, p| 5, [0, 0, 0], #{thicknes: 1})", "thicknes"),
    ] {
        let err = load_script(Path::new("names.rhai"), src, &[])
            .err()
            .unwrap_or_else(|| panic!("{src} loaded"))
            .to_string();
        assert!(err.contains(key), "{src}: {err}");
    }
}
