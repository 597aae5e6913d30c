//! A printer that resets, halts or goes silent mid-job: the job stops with the right error in
//! bounded time, and the journal lets a resume finish it with nothing executed twice.

use crate::support::*;
use isoforge_host::fake::{FakePrinter, Faults};
use isoforge_host::gcode::Program;
use isoforge_host::journal::{self, JournalRecord, Status};
use isoforge_host::streamer::Report;

struct Interrupted {
    text: String,
    program: Program,
    journal: std::path::PathBuf,
    report: Report,
    _dir: tempfile::TempDir,
}

fn interrupted(printer: &FakePrinter) -> Interrupted {
    let (text, program) = vase(JOB_COMMANDS);
    let dir = tempfile::tempdir().expect("a temp dir");
    let path = dir.path().join("vase.gcode.journal");
    let report = print(
        printer,
        &program,
        0,
        vec![],
        Some(new_journal(&path, &text, &program)),
    );
    assert!(!report.completed);
    // Bounded: stopped within a few probe timeouts, not hung.
    assert!(report.seconds < 30.0, "took {} s", report.seconds);
    Interrupted {
        text,
        program,
        journal: path,
        report,
        _dir: dir,
    }
}

/// Resumes from the journal on `printer`; returns the number of prelude commands.
fn resume(job: &Interrupted, printer: &FakePrinter) -> usize {
    let record = JournalRecord::load(&job.journal).expect("journal");
    assert_eq!(record.status, Status::Failed);
    assert_eq!(record.executed, job.report.executed);
    let fp = journal::fingerprint(job.text.as_bytes());
    let plan = journal::plan_resume(&job.program, fp, Some(&record), None).expect("plan");
    assert_eq!(plan.start, record.executed);
    let mut fresh = new_journal(&job.journal, &job.text, &job.program);
    fresh.1.executed = plan.start;
    fresh.1.state = plan.state.clone();
    let n = plan.prelude.len();
    let report = print(printer, &job.program, plan.start, plan.prelude, Some(fresh));
    assert!(report.completed, "{:?}", report.error);
    let after = JournalRecord::load(&job.journal).expect("journal");
    assert_eq!(after.status, Status::Completed);
    assert_eq!(after.executed, job.program.commands.len());
    n
}

/// First run's commands + second run's (prelude removed) must be the file, exactly once.
fn check_once(first: &[String], second: &[String], prelude: usize, program: &Program) {
    let mut all = first.to_vec();
    all.extend_from_slice(&second[prelude..]);
    assert_same(&all, &texts(program), "both runs");
}

#[test]
fn reset_mid_job_then_resume_on_the_same_printer() {
    let printer = fake(Faults {
        reset_at: Some(7_000),
        seed: 11,
        ..Faults::default()
    });
    let job = interrupted(&printer);
    let err = job.report.error.as_ref().expect("an error").to_string();
    assert!(err.contains("reset"), "{err}");
    let first = job_commands(&printer.executed());
    assert_eq!(first.len(), job.report.executed, "journal = what ran");
    let before = printer.executed().len();
    let prelude = resume(&job, &printer);
    let second = job_commands(&printer.executed()[before..]);
    check_once(&first, &second, prelude, &job.program);
}

#[test]
fn halt_then_resume_on_a_power_cycled_printer() {
    let a = fake(Faults {
        halt_at: Some(5_000),
        ..Faults::default()
    });
    let job = interrupted(&a);
    let err = job.report.error.as_ref().expect("an error").to_string();
    assert!(err.contains("halted"), "{err}");
    let b = fake(Faults::default());
    let prelude = resume(&job, &b);
    check_once(
        &job_commands(&a.executed()),
        &job_commands(&b.executed()),
        prelude,
        &job.program,
    );
}

#[test]
fn silence_then_resume_on_a_power_cycled_printer() {
    let a = fake(Faults {
        silent_at: Some(12_000),
        ..Faults::default()
    });
    let job = interrupted(&a);
    let err = job.report.error.as_ref().expect("an error").to_string();
    assert!(
        err.contains("stopped answering") && err.contains("last acknowledged"),
        "{err}"
    );
    let b = fake(Faults::default());
    let prelude = resume(&job, &b);
    check_once(
        &job_commands(&a.executed()),
        &job_commands(&b.executed()),
        prelude,
        &job.program,
    );
}

#[test]
fn resume_prelude_restores_the_printer_state() {
    let a = fake(Faults {
        reset_at: Some(3_000),
        ..Faults::default()
    });
    let job = interrupted(&a);
    let record = JournalRecord::load(&job.journal).expect("journal");
    let fp = journal::fingerprint(job.text.as_bytes());
    let plan = journal::plan_resume(&job.program, fp, Some(&record), None).expect("plan");
    // The vase heats bed 60 / hotend 200, prints with relative E in absolute XYZ.
    for want in [
        "M140 S60",
        "M104 S200",
        "M190 S60",
        "M109 S200",
        "G28 X Y",
        "G90",
        "M83",
    ] {
        assert!(
            plan.prelude.iter().any(|c| c == want),
            "{want} in {:?}",
            plan.prelude
        );
    }
    assert!(plan.summary.contains("heat"), "{}", plan.summary);
}

#[test]
fn from_layer_starts_at_the_layer() {
    let (_, program) = vase(3_000);
    let layer = program.layer(10).expect("layer 10").clone();
    let plan = journal::plan_resume(&program, 0, None, Some(10)).expect("plan");
    let printer = fake(Faults::default());
    let report = print(&printer, &program, plan.start, plan.prelude.clone(), None);
    assert!(report.completed);
    let done = job_commands(&printer.executed());
    assert_same(
        &done[plan.prelude.len()..],
        &texts(&program)[layer.first_command..],
        "from layer 10",
    );
}
