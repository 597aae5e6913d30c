//! Finer where the mesh misses: the blocks of the lattice around the places where a mesh is
//! farther from the model's surface than the tolerance are sampled on a lattice up to
//! `isoforge_mesh::MAX_REFINE_LEVELS` levels finer, round after round, until the tolerance holds
//! or no round does better (docs/meshing.md, "Finer where it misses").
//!
//! Round 0 is the mesh at the lattice asked for. Its misses are found by measuring it whole
//! (`--max-depth`) or, by default, from the places the mesher's splits had to leave off the
//! surface (`left_off.rs`), which costs nothing when the mesh holds. Each later round
//! refines the blocks within [`MARGIN_CELLS`] of every miss found so far, two levels finer
//! first; when its misses are all in blocks already refined, the next round goes a level
//! finer there. Every refined mesh is measured whole. The best mesh is kept; the others'
//! temporary files are dropped.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::Result;
use isoforge_field::ClippedField;
use isoforge_mesh::{Estimate, MeshSettings, Refinement, beyond};
use serde_json::{Value, json};

use super::attempt::{self, Attempt, Job};
use super::left_off::LeftOff;
use crate::common::Global;

/// A miss within this many cells of a block's face refines the block across too: a refined
/// block's face keeps the coarse lattice's surface (the seam), so a miss right beside it
/// stays unless the block across is refined as well. At 0, sinus_bugs kept a miss 0.17
/// cells from a seam (1.25 tolerances) round after round; at 2 it held in two rounds.
const MARGIN_CELLS: f64 = 2.0;

/// The levels the first refining round goes finer: two held gyroid_sphere, sinus_sphere,
/// spiky_ball and stacked_sphere_circle at depth 8 in one or two rounds (a lattice one
/// level finer missed on four of the nine fixtures that miss there, docs/meshing.md).
const FIRST_LEVELS: u8 = 2;

/// Rounds of refining at most, after the first mesh.
const MAX_ROUNDS: usize = 4;

/// The fine blocks any refinement may add, whatever the model's size: a small model's
/// budget in multiples of its own blocks is too small to refine its misses by three
/// levels (curve_cyl has 53 blocks at depth 8, and 12 of them refined 3 levels are 768
/// fine blocks). As many as a depth-8 mesh of a ball has blocks.
const BUDGET_FLOOR: f64 = 1024.0;

/// How far the mesh may be refined.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plan {
    /// The most levels finer a block may be sampled; 0 refines nothing.
    pub levels: u8,
    /// Whether the first mesh is measured whole (`--max-depth`), rather than told by its
    /// places; refined meshes always are.
    pub measure: bool,
    /// The most fine blocks a refinement may add, as a multiple of the first mesh's
    /// blocks: about the most extra sampling it may cost.
    pub budget: f64,
}

/// The rounds' outcome: the mesh kept, and what each round did.
pub(super) struct Rounds {
    /// The mesh kept (to commit).
    pub kept: Attempt,
    /// Each round, for `--json`.
    pub rounds: Vec<Value>,
    /// The first mesh's places left off the surface, measured (when it was not measured
    /// whole), and where they miss.
    pub places: Option<LeftOff>,
    /// Whether any round refined.
    pub refined: bool,
}

/// Meshes the job round after round as the plan allows, each estimate from `fit` (which
/// refuses what does not fit in memory).
pub(super) fn run(
    job: &Job,
    settings: MeshSettings,
    plan: Plan,
    global: &Global,
    fit: &dyn Fn(&MeshSettings) -> Result<Estimate>,
) -> Result<Rounds> {
    let tolerance = settings.effective_tolerance();
    let field = ClippedField::new(&job.loaded.model.shape, settings.bounds);
    // A round's misses: the measured mesh's points beyond, or its places beyond.
    let misses_of = |made: &Attempt| -> (Vec<([f64; 3], f64)>, Option<LeftOff>) {
        if made.deviation.is_some() {
            return (made.misses.clone(), None);
        }
        let places = LeftOff::measure(job.loaded, &made.settings, &made.notes);
        let misses = if places.missed() {
            beyond(&field, &places.points, tolerance)
        } else {
            Vec::new()
        };
        (misses, Some(places))
    };
    let began = Instant::now();
    let estimate = fit(&settings)?;
    let first = attempt::attempt(job, settings.clone(), estimate, global, plan.measure)?;
    let (mut misses, mut places) = misses_of(&first);
    let mut rounds = vec![round_json(&first, began, None, &misses)];
    let base_blocks = first.notes.blocks.load(Ordering::Relaxed) as f64;
    let budget = (plan.budget * base_blocks).max(BUDGET_FLOOR);
    let mut kept = first;
    let mut kept_max = worst(&kept, &misses);
    if misses.is_empty() || plan.levels == 0 {
        return Ok(Rounds {
            kept,
            rounds,
            places,
            refined: false,
        });
    }
    let mut wanted: HashMap<[i64; 3], f64> = HashMap::new();
    let mut refined = false;
    let mut levels = FIRST_LEVELS.min(plan.levels);
    let mut last: Option<Refinement> = None;
    for _ in 0..MAX_ROUNDS {
        let near = Refinement::blocks_near(&settings.bounds, settings.depth, &misses, MARGIN_CELLS);
        let before = wanted.len();
        for (b, d) in near {
            let e = wanted.entry(b).or_insert(0.0);
            *e = e.max(d);
        }
        if wanted.len() == before && last.is_some() {
            // Every miss is in a block refined already: finer there, if allowed.
            if levels >= plan.levels {
                break;
            }
            levels += 1;
        }
        let refinement = within_budget(&wanted, levels, budget);
        if last.as_ref() == Some(&refinement) {
            break;
        }
        let mut next = settings.clone();
        next.refine = Some(Arc::new(refinement.clone()));
        let estimate = match fit(&next) {
            Ok(e) => e,
            Err(e) => {
                if !global.quiet {
                    eprintln!("note: {e:#}; not refining further");
                }
                break;
            }
        };
        let began = Instant::now();
        // Refined meshes are measured whole: the places say too little of a mesh that
        // changed (on curve_cyl none was beyond where `check` found 3.2 tolerances).
        let made = attempt::attempt(job, next, estimate, global, true)?;
        refined = true;
        let (new_misses, new_places) = misses_of(&made);
        rounds.push(round_json(&made, began, Some(&refinement), &new_misses));
        let max = worst(&made, &new_misses);
        last = Some(refinement);
        misses = new_misses;
        if max < kept_max || misses.is_empty() {
            kept = made;
            kept_max = max;
            places = new_places;
        }
        if misses.is_empty() {
            break;
        }
    }
    Ok(Rounds {
        kept,
        rounds,
        places,
        refined,
    })
}

/// A round's largest miss: measured, or the farthest place beyond (0 when none is).
fn worst(made: &Attempt, misses: &[([f64; 3], f64)]) -> f64 {
    match made.deviation {
        Some(d) => d.max,
        None => misses.iter().map(|m| m.1).fold(0.0, f64::max),
    }
}

/// The blocks to refine by `levels`: all wanted, unless their fine blocks would be more
/// than `budget`; then the farthest-missing first, as many as fit.
fn within_budget(wanted: &HashMap<[i64; 3], f64>, levels: u8, budget: f64) -> Refinement {
    let per_block = 4f64.powi(i32::from(levels));
    let fits = (budget / per_block).floor().max(1.0) as usize;
    let mut order: Vec<(&[i64; 3], &f64)> = wanted.iter().collect();
    // Farthest first; the coordinates make the order the same on every run.
    order.sort_by(|a, b| b.1.total_cmp(a.1).then(a.0.cmp(b.0)));
    Refinement {
        levels,
        blocks: order.into_iter().take(fits).map(|(b, _)| *b).collect(),
    }
}

/// One round for `--json`.
fn round_json(
    made: &Attempt,
    began: Instant,
    refinement: Option<&Refinement>,
    misses: &[([f64; 3], f64)],
) -> Value {
    json!({
        "levels": refinement.map_or(0, |r| r.levels),
        "blocks_refined": refinement.map_or(0, |r| r.blocks.len()),
        "triangles": made.report.tally.triangles,
        "max_deviation": made.deviation.map(|d| d.max),
        "misses": misses.len(),
        "seconds": began.elapsed().as_secs_f64(),
    })
}
