//! Finer where the mesh misses: the blocks of the lattice around the places where a mesh is
//! farther from the model's surface than the tolerance are sampled on a lattice up to
//! `isoforge_mesh::MAX_REFINE_LEVELS` levels finer, round after round, until the tolerance holds
//! or no round does better (docs/meshing.md, "Finer where it misses").
//!
//! Round 0 is the mesh at the lattice asked for. Its misses are found by measuring it whole
//! (`--max-depth`) or, by default, from the places the mesher's splits had to leave off the
//! surface (`left_off.rs`; those beyond [`NEAR_SHARE`] of the tolerance), which costs
//! nothing when the mesh holds. Each later round
//! refines the blocks within [`MARGIN_CELLS`] of every miss found so far, two levels finer
//! first; when its misses are all in blocks already refined, the next round goes a level
//! finer there, or, at the finest level allowed, merges their leaves under the fine
//! lattice's tolerance (one round). Every refined mesh is measured whole. The best mesh is kept; the others'
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

/// A place this share of the tolerance from the surface starts the refining, as one beyond
/// it does. The places are a few points of the mesh: where the farthest is nearly at the
/// tolerance, the mesh beside it may be beyond. On spiky_ball at depth 8 the farthest place
/// is 0.968 tolerances off and `check` finds 1.54 at the pole, which no place names; of
/// the other fixtures that hold, the farthest place is at most 0.70 (hull_mixed).
const NEAR_SHARE: f64 = 0.9;

/// Rounds of refining at most, after the first mesh.
const MAX_ROUNDS: usize = 4;

/// The fine blocks any refinement may add, whatever the model's size: a small model's
/// budget in multiples of its own blocks is too small to refine its misses by three
/// levels (curve_cyl has 53 blocks at depth 8, and 12 of them refined 3 levels are 768
/// fine blocks; spaceship has 99, and its 29 that miss refined 3 levels are 1,856). The
/// rounds' time limit bounds what they cost.
const BUDGET_FLOOR: f64 = 4096.0;

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
    /// The longest the rounds may take, as a multiple of the first mesh's time (and at
    /// least [`SECONDS_FLOOR`]); `None` for no limit.
    pub seconds: Option<f64>,
}

/// Seconds the rounds may always take, however quick the first mesh was.
const SECONDS_FLOOR: f64 = 30.0;

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
        let near = NEAR_SHARE * tolerance;
        // (Measured only when they can start a refining: each is searched around.)
        let misses = if plan.levels > 0 && places.max > near {
            beyond(&field, &places.points, near)
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
    // A mesh told by its places only is beaten by any measured one.
    let mut kept_max = match kept.deviation {
        Some(d) => d.max,
        None => f64::INFINITY,
    };
    // Thin almost everywhere, the model needs a finer lattice all over, not a few blocks:
    // the plain mesh is kept with its note (the 2 % is `mesh.rs`'s thin note's; fuzz cases
    // of offsets of thin shells had 3 % and 14 %, and refining took them from 0.6 s to 19 s
    // and 4 s to 12 s without holding; the fixtures that hold when refined have 0.3 % at
    // most).
    let thin = kept.notes.thin_triangles.load(Ordering::Relaxed);
    let thin_everywhere =
        !plan.measure && thin * super::THIN_NOTE_SHARE >= kept.report.tally.triangles;
    if misses.is_empty() || plan.levels == 0 || thin_everywhere {
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
    let mut tight = false;
    let mut last: Option<Refinement> = None;
    let first_seconds = began.elapsed().as_secs_f64();
    // The last round's seconds per fine block, to foresee the next one's.
    let mut per_fine_block: Option<f64> = None;
    for _ in 0..MAX_ROUNDS {
        let near = Refinement::blocks_near(&settings.bounds, settings.depth, &misses, MARGIN_CELLS);
        let before = wanted.len();
        for (b, d) in near {
            let e = wanted.entry(b).or_insert(0.0);
            *e = e.max(d);
        }
        if wanted.len() == before && last.is_some() {
            // Every miss is in a block refined already: finer there, if allowed and if
            // the budget holds every block wanted at that level (a finer level on fewer
            // blocks gives back the misses the others had held: spaceship at three levels
            // on 23 blocks missed by 3.10 tolerances where two levels on 29 gave 2.43).
            let finer = wanted.len() as f64 * fine_blocks_per_block(levels + 1);
            if levels < plan.levels && finer <= budget {
                levels += 1;
            } else if !tight {
                // No finer lattice: the same blocks once more with their leaves merged as
                // the fine lattice's tolerance allows (`Refinement::tight_merges`).
                tight = true;
            } else {
                break;
            }
        }
        let mut refinement = within_budget(&wanted, levels, budget);
        refinement.tight_merges = tight;
        if last.as_ref() == Some(&refinement) {
            break;
        }
        let fine_blocks = refinement.blocks.len() as f64 * fine_blocks_per_block(levels);
        if let (Some(cap), Some(rate)) = (plan.seconds, per_fine_block) {
            let allowed = (cap * first_seconds).max(SECONDS_FLOOR);
            let foreseen = began.elapsed().as_secs_f64() + first_seconds + rate * fine_blocks;
            if foreseen > allowed {
                if !global.quiet {
                    eprintln!(
                        "note: refining stopped after {:.1} s: the next round would take the \
                         run past {allowed:.0} s; --max-depth refines without this limit",
                        began.elapsed().as_secs_f64()
                    );
                }
                break;
            }
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
        let began_round = Instant::now();
        // Refined meshes are measured whole: the places say too little of a mesh that
        // changed (on curve_cyl none was beyond where `check` found 3.2 tolerances).
        let made = attempt::attempt(job, next, estimate, global, true)?;
        refined = true;
        // What the fine blocks cost, past a plain mesh's time.
        let round_seconds = began_round.elapsed().as_secs_f64() - first_seconds;
        per_fine_block = Some(round_seconds.max(0.0) / fine_blocks.max(1.0));
        let (new_misses, new_places) = misses_of(&made);
        rounds.push(round_json(
            &made,
            began_round,
            Some(&refinement),
            &new_misses,
        ));
        let max = made.deviation.map_or(f64::INFINITY, |d| d.max);
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

/// The fine blocks a refined block costs about: those its surface crosses.
fn fine_blocks_per_block(levels: u8) -> f64 {
    4f64.powi(i32::from(levels))
}

/// The blocks to refine by `levels`: all wanted, unless their fine blocks would be more
/// than `budget`; then the farthest-missing first, as many as fit.
fn within_budget(wanted: &HashMap<[i64; 3], f64>, levels: u8, budget: f64) -> Refinement {
    let per_block = fine_blocks_per_block(levels);
    let fits = (budget / per_block).floor().max(1.0) as usize;
    let mut order: Vec<(&[i64; 3], &f64)> = wanted.iter().collect();
    // Farthest first; the coordinates make the order the same on every run.
    order.sort_by(|a, b| b.1.total_cmp(a.1).then(a.0.cmp(b.0)));
    Refinement {
        levels,
        blocks: order.into_iter().take(fits).map(|(b, _)| *b).collect(),
        tight_merges: false,
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
        "tight_merges": refinement.is_some_and(|r| r.tight_merges),
        "triangles": made.report.tally.triangles,
        "max_deviation": made.deviation.map(|d| d.max),
        "misses": misses.len(),
        "seconds": began.elapsed().as_secs_f64(),
    })
}
