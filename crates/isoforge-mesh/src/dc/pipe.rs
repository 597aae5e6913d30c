//! The stages behind the emitter on a thread of their own: the edge collapses, the splits,
//! the small parts' check and the writer take the emitter's vertices and triangles in
//! order, in chunks over a bounded channel, while the workers build the next slab.
//!
//! Those stages are serial (each decision depends on the ones before it), and before they
//! had a thread of their own they ran between the slabs, with the workers idle: on
//! gyroid_sphere at depth 9 the main thread did 37 % of the CPU work with the other core
//! waiting (docs/meshing.md, "The stages behind the mesher on their own thread"). The
//! order of what reaches the sink is unchanged, so the output is the same bytes.

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

use super::MeshError;
use crate::sink::MeshSink;

/// Events per chunk: large enough that the channel's cost per event is small (a send
/// wakes the other thread), small enough that the stages behind start early.
const CHUNK: usize = 8192;

/// Chunks that may wait in the channel: at most this many (about 430 kB each, 27 MB in
/// all) whatever the mesh's size. The two ends' speeds change from slab to slab, and a
/// deeper pipe evens that out: against 16, 4 took 1.07 to 1.11 of the time at depth 9
/// (gyroid_sphere, sinus_sphere) and 64 took 0.92 to 0.94, with peaks within 2 MiB (it
/// seldom fills; gyroid_sphere at depth 10 peaks at 99 MiB with either).
const CHUNKS_IN_FLIGHT: usize = 64;

/// One call on a [`MeshSink`], kept to be replayed.
enum Event {
    Vertex([f32; 3]),
    Triangle([u32; 3], [[f32; 3]; 3]),
}

/// What goes over the channel.
enum Message {
    Events(Vec<Event>),
    /// Everything was sent: the stages behind may finish.
    End,
}

/// The emitter's end of the pipe: a [`MeshSink`] that queues what it is given.
pub struct Pipe {
    tx: SyncSender<Message>,
    chunk: Vec<Event>,
    /// Set when the pipe is dropped without its end, so that the drain stops at once
    /// instead of working through the chunks still waiting (a cancel is then prompt).
    abandoned: Arc<AtomicBool>,
    ended: bool,
}

/// The stages' end of the pipe.
pub struct Drain {
    rx: Receiver<Message>,
    abandoned: Arc<AtomicBool>,
}

/// A pipe and its drain.
pub fn pipe() -> (Pipe, Drain) {
    let (tx, rx) = sync_channel(CHUNKS_IN_FLIGHT);
    let abandoned = Arc::new(AtomicBool::new(false));
    (
        Pipe {
            tx,
            chunk: Vec::with_capacity(CHUNK),
            abandoned: abandoned.clone(),
            ended: false,
        },
        Drain { rx, abandoned },
    )
}

impl Pipe {
    fn push(&mut self, e: Event) -> io::Result<()> {
        self.chunk.push(e);
        if self.chunk.len() >= CHUNK {
            let full = std::mem::replace(&mut self.chunk, Vec::with_capacity(CHUNK));
            self.send(Message::Events(full))?;
        }
        Ok(())
    }

    fn send(&self, m: Message) -> io::Result<()> {
        // The receiver is gone only when the stages behind stopped on an error of their
        // own, which the caller takes from their thread.
        self.tx
            .send(m)
            .map_err(|_| io::Error::other("the stages behind the mesher stopped"))
    }

    /// Sends what is queued and says that nothing more comes.
    pub fn end(mut self) -> io::Result<()> {
        self.ended = true;
        let rest = std::mem::take(&mut self.chunk);
        if !rest.is_empty() {
            self.send(Message::Events(rest))?;
        }
        self.send(Message::End)
    }
}

impl Drop for Pipe {
    fn drop(&mut self) {
        if !self.ended {
            self.abandoned.store(true, Ordering::Relaxed);
        }
    }
}

impl MeshSink for Pipe {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.push(Event::Vertex(p))
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.push(Event::Triangle(t, corners))
    }
}

impl Drain {
    /// Replays everything sent into `sink`, in order. `Ok` once the pipe's end came;
    /// [`MeshError::Cancelled`] when the pipe was dropped without it (the emitter stopped;
    /// its own error is the one to report).
    pub fn into_sink(self, sink: &mut dyn MeshSink) -> Result<(), MeshError> {
        for m in self.rx {
            if self.abandoned.load(Ordering::Relaxed) {
                break;
            }
            match m {
                Message::End => return Ok(()),
                Message::Events(events) => {
                    for e in events {
                        match e {
                            Event::Vertex(p) => sink.vertex(p),
                            Event::Triangle(t, c) => sink.triangle(t, c),
                        }
                        .map_err(MeshError::Write)?;
                    }
                }
            }
        }
        Err(MeshError::Cancelled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    #[test]
    fn what_goes_in_comes_out_in_order_across_chunks() {
        let (mut p, d) = pipe();
        let n = 3 * CHUNK + 5;
        let got = std::thread::scope(|s| {
            let h = s.spawn(move || {
                let mut m = Mesh::default();
                d.into_sink(&mut m).map(|()| m)
            });
            for i in 0..n {
                p.vertex([i as f32, 0.0, 0.0]).unwrap();
                if i >= 2 {
                    p.triangle([i as u32 - 2, i as u32 - 1, i as u32], [[0.0; 3]; 3])
                        .unwrap();
                }
            }
            p.end().unwrap();
            h.join().unwrap()
        });
        let m = got.unwrap();
        assert_eq!(m.vertices.len(), n);
        assert_eq!(m.triangles.len(), n - 2);
        assert!(m.vertices.iter().enumerate().all(|(i, v)| v[0] == i as f32));
        assert!(
            m.triangles
                .iter()
                .enumerate()
                .all(|(i, t)| t[2] == i as u32 + 2)
        );
    }

    #[test]
    fn a_pipe_dropped_without_its_end_is_not_finished_nor_drained() {
        let (mut p, d) = pipe();
        // Two full chunks wait in the channel when the pipe is dropped.
        for _ in 0..2 * CHUNK {
            p.vertex([1.0, 2.0, 3.0]).unwrap();
        }
        drop(p);
        let mut m = Mesh::default();
        assert!(matches!(d.into_sink(&mut m), Err(MeshError::Cancelled)));
        assert!(
            m.vertices.is_empty(),
            "{} vertices drained",
            m.vertices.len()
        );
    }

    /// A sink that refuses its second triangle.
    struct Refusing(usize);
    impl MeshSink for Refusing {
        fn vertex(&mut self, _: [f32; 3]) -> io::Result<()> {
            Ok(())
        }
        fn triangle(&mut self, _: [u32; 3], _: [[f32; 3]; 3]) -> io::Result<()> {
            self.0 += 1;
            if self.0 == 2 {
                Err(io::Error::other("disk full"))
            } else {
                Ok(())
            }
        }
    }

    #[test]
    fn a_sink_s_error_stops_the_sender() {
        let (mut p, d) = pipe();
        let (sent, drained) = std::thread::scope(|s| {
            let h = s.spawn(move || d.into_sink(&mut Refusing(0)));
            // Far more than the channel holds: the sender must see the stop, not block.
            let mut sent = Ok(());
            for _ in 0..(CHUNKS_IN_FLIGHT + 4) * CHUNK {
                sent = p.triangle([0, 1, 2], [[0.0; 3]; 3]);
                if sent.is_err() {
                    break;
                }
            }
            drop(p);
            (sent, h.join().unwrap())
        });
        assert!(sent.is_err(), "the sender went on after the sink failed");
        match drained {
            Err(MeshError::Write(e)) => assert_eq!(e.to_string(), "disk full"),
            other => panic!("expected the sink's error, got {other:?}"),
        }
    }
}
