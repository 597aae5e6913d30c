//! Pause, resume and cancel through the streamer's `Control`, against the fake printer.

use std::time::Duration;

use crate::support::*;
use isoforge_host::fake::Faults;
use isoforge_host::streamer::{self, Control, Job, Update};

#[test]
fn pause_holds_the_job_and_resume_finishes_it() {
    let (_, program) = vase(20_000);
    let printer = fake(Faults::default());
    let control = Control::new();
    let report = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let mut port = streamer::open_port(printer.path(), 115_200).expect("open");
            let job = Job {
                program: &program,
                start: 0,
                prelude: vec![],
                journal: None,
            };
            streamer::stream(&mut *port, job, test_config(), &control, |_| {})
        });
        // Let it run, pause, and check nothing more executes while paused.
        while printer.executed().len() < 2_000 {
            std::thread::sleep(Duration::from_millis(5));
        }
        control.pause();
        std::thread::sleep(Duration::from_millis(300));
        let paused_at = printer.executed().len();
        std::thread::sleep(Duration::from_millis(500));
        assert_eq!(
            printer.executed().len(),
            paused_at,
            "nothing is sent while paused"
        );
        assert!(paused_at < program.commands.len());
        control.resume();
        worker.join().expect("no panic")
    });
    assert!(report.completed, "{:?}", report.error);
    assert_same(
        &job_commands(&printer.executed()),
        &texts(&program),
        "paused and resumed",
    );
}

#[test]
fn cancel_stops_sending_then_turns_heaters_and_motors_off() {
    let (_, program) = vase(20_000);
    let printer = fake(Faults::default());
    let control = Control::new();
    let mut saw_progress = false;
    let report = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let mut port = streamer::open_port(printer.path(), 115_200).expect("open");
            let job = Job {
                program: &program,
                start: 0,
                prelude: vec![],
                journal: None,
            };
            streamer::stream(&mut *port, job, test_config(), &control, |u| {
                if let Update::Progress(p) = u {
                    saw_progress |= p.executed > 0 && p.percent > 0.0;
                }
            })
        });
        while printer.executed().len() < 1_000 {
            std::thread::sleep(Duration::from_millis(5));
        }
        control.cancel();
        worker.join().expect("no panic")
    });
    assert!(report.cancelled && !report.completed);
    assert!(saw_progress);
    let done = job_commands(&printer.executed());
    let n = done.len();
    assert!(n < program.commands.len());
    assert_eq!(done[n - 3..], ["M104 S0", "M140 S0", "M84"]);
    // Everything before the shutdown is the file's beginning, once.
    assert_same(
        &done[..n - 3],
        &texts(&program)[..n - 3],
        "before the cancel",
    );
}

#[test]
fn emergency_cancel_sends_m112_and_the_printer_halts() {
    let (_, program) = vase(20_000);
    let printer = fake(Faults::default());
    let control = Control::new();
    let report = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let mut port = streamer::open_port(printer.path(), 115_200).expect("open");
            let job = Job {
                program: &program,
                start: 0,
                prelude: vec![],
                journal: None,
            };
            streamer::stream(&mut *port, job, test_config(), &control, |_| {})
        });
        while printer.executed().len() < 1_000 {
            std::thread::sleep(Duration::from_millis(5));
        }
        control.emergency();
        worker.join().expect("no panic")
    });
    assert!(report.cancelled);
    std::thread::sleep(Duration::from_millis(200));
    let n = printer.executed().len();
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(printer.executed().len(), n, "halted: nothing more runs");
    assert!(n < program.commands.len());
}
