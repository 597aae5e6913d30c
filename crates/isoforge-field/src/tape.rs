//! Tapes: a graph flattened to SSA instructions with allocated registers, and their
//! simplification by the choices an interval pass recorded.
//!
//! The graph is first flattened to SSA form (instruction `i` defines value `i`), then
//! registers are allocated by a linear scan from the output backwards (as fidget does):
//! a value takes a register at its last use and gives it back at its definition, so a
//! few registers serve a long tape and the batch evaluator's working set stays in cache.
//! Constant operands of binary operations are immediates, so `x * 2` is one instruction.
//!
//! [`Tape::simplify`] works directly on the register form in one backward pass: liveness
//! (a register is needed if a live instruction later reads it), replacement of decided
//! min/max instructions by their kept operand, and allocation of fresh registers, all at
//! once. Scratch buffers live in a thread-local, so a simplification allocates only the
//! new tape.

use std::sync::Arc;

use crate::context::{Context, Node, NodeId};
use crate::custom::CustomField;
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::{Shape, Var};

/// Which side of a min or max matters on a region.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Choice {
    /// Only the left argument can win: the right branch may be dropped.
    Left,
    /// Only the right argument can win.
    Right,
    /// Either may win (or it is unknown).
    Both,
}

/// One instruction in SSA form: operands are indices of earlier instructions.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum Ssa {
    Var(Var),
    Const(f64),
    Unary(UnaryOp, u32),
    Binary(BinaryOp, u32, u32),
    /// `a op imm`
    BinaryRI(BinaryOp, u32, f64),
    /// `imm op b`
    BinaryIR(BinaryOp, f64, u32),
    /// Custom node number `.0` at the point given by three values.
    Custom(u32, [u32; 3]),
}

/// One instruction in register form: `out` and operands are register numbers. The
/// allocator guarantees `out` differs from every operand register, so evaluators may
/// borrow the output mutably and the operands shared.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum Op {
    Var {
        out: u32,
        v: Var,
    },
    Const {
        out: u32,
        c: f64,
    },
    Unary {
        op: UnaryOp,
        out: u32,
        a: u32,
    },
    Binary {
        op: BinaryOp,
        out: u32,
        a: u32,
        b: u32,
    },
    BinaryRI {
        op: BinaryOp,
        out: u32,
        a: u32,
        imm: f64,
    },
    BinaryIR {
        op: BinaryOp,
        out: u32,
        imm: f64,
        b: u32,
    },
    Custom {
        k: u32,
        out: u32,
        args: [u32; 3],
    },
    /// `out = a` (left by simplification where a kept operand already had a register).
    Copy {
        out: u32,
        a: u32,
    },
}

impl Op {
    fn is_choice(&self) -> bool {
        matches!(
            self,
            Op::Binary {
                op: BinaryOp::Min | BinaryOp::Max,
                ..
            } | Op::BinaryRI {
                op: BinaryOp::Min | BinaryOp::Max,
                ..
            } | Op::BinaryIR {
                op: BinaryOp::Min | BinaryOp::Max,
                ..
            }
        )
    }
}

struct TapeData {
    ops: Vec<Op>,
    regs: usize,
    choices: usize,
    /// The register holding the result after the last instruction.
    out: u32,
    /// Shared by a tape and all its simplifications (indices stay valid); a narrowed tape
    /// has its own list, with the same indices.
    customs: Arc<[Arc<dyn CustomField>]>,
}

/// An evaluable program. Cheap to clone (shared).
#[derive(Clone)]
pub struct Tape(Arc<TapeData>);

impl std::fmt::Debug for Tape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tape")
            .field("len", &self.len())
            .field("registers", &self.0.regs)
            .field("choices", &self.0.choices)
            .finish()
    }
}

impl Tape {
    /// Compiles a shape (dedupe, fold, flatten, allocate registers).
    pub fn new(shape: &Shape) -> Tape {
        let mut ctx = Context::new();
        let root = ctx.import(shape);
        Tape::from_context(&ctx, root)
    }

    /// Compiles the graph below `root` in a context.
    pub fn from_context(ctx: &Context, root: NodeId) -> Tape {
        // Nodes reachable from root, in id order (operands have smaller ids, so id order
        // is a topological order). Constants used only as binary operands become
        // immediates and get no instruction.
        let n = root.0 as usize + 1;
        let mut reach = vec![false; n];
        let mut needs_slot = vec![false; n];
        reach[root.0 as usize] = true;
        needs_slot[root.0 as usize] = true;
        for i in (0..n).rev() {
            if !reach[i] {
                continue;
            }
            let mut mark = |id: NodeId, slot: bool| {
                reach[id.0 as usize] = true;
                needs_slot[id.0 as usize] |= slot;
            };
            match ctx.node(NodeId(i as u32)) {
                Node::Var(_) | Node::Const(_) => {}
                Node::Unary(_, a) => mark(*a, true),
                Node::Binary(_, a, b) => {
                    let (ca, cb) = (ctx.as_constant(*a).is_some(), ctx.as_constant(*b).is_some());
                    mark(*a, !ca || cb);
                    mark(*b, !cb || ca);
                }
                Node::Custom(_, ins) => ins.iter().for_each(|&a| mark(a, true)),
            }
        }
        let mut slot = vec![u32::MAX; n];
        let mut ssa = Vec::new();
        let mut customs: Vec<Arc<dyn CustomField>> = Vec::new();
        for i in 0..n {
            if !reach[i] {
                continue;
            }
            let node = ctx.node(NodeId(i as u32));
            if matches!(node, Node::Const(_)) && !needs_slot[i] {
                continue;
            }
            let s = |id: &NodeId| slot[id.0 as usize];
            let op = match node {
                Node::Var(v) => Ssa::Var(*v),
                Node::Const(c) => Ssa::Const(*c),
                Node::Unary(op, a) => Ssa::Unary(*op, s(a)),
                Node::Binary(op, a, b) => match (ctx.as_constant(*a), ctx.as_constant(*b)) {
                    (None, Some(c)) => Ssa::BinaryRI(*op, s(a), c),
                    (Some(c), None) => Ssa::BinaryIR(*op, c, s(b)),
                    _ => Ssa::Binary(*op, s(a), s(b)),
                },
                Node::Custom(f, ins) => {
                    customs.push(f.clone());
                    Ssa::Custom(
                        customs.len() as u32 - 1,
                        [s(&ins[0]), s(&ins[1]), s(&ins[2])],
                    )
                }
            };
            slot[i] = ssa.len() as u32;
            ssa.push(op);
        }
        let (ops, regs) = allocate(&ssa);
        Tape::from_ops(ops, regs, customs.into())
    }

    fn from_ops(ops: Vec<Op>, regs: usize, customs: Arc<[Arc<dyn CustomField>]>) -> Tape {
        let choices = ops.iter().filter(|o| o.is_choice()).count();
        // The allocator gives the output register 0.
        Tape(Arc::new(TapeData {
            ops,
            regs: regs.max(1),
            choices,
            out: 0,
            customs,
        }))
    }

    /// The number of instructions.
    pub fn len(&self) -> usize {
        self.0.ops.len()
    }
    /// True for a tape with no instructions (never: a tape has at least its output).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The number of min and max instructions; an [`crate::IntervalEval`] records this many
    /// choices.
    pub fn choice_count(&self) -> usize {
        self.0.choices
    }
    /// True when the tape holds a custom node (whose own tape may narrow).
    pub fn has_custom_nodes(&self) -> bool {
        !self.0.customs.is_empty()
    }
    /// The number of registers an evaluator needs.
    pub fn register_count(&self) -> usize {
        self.0.regs
    }
    /// The register instructions, in evaluation order.
    pub(crate) fn ops(&self) -> &[Op] {
        &self.0.ops
    }
    /// The register holding the result.
    pub(crate) fn output(&self) -> usize {
        self.0.out as usize
    }
    /// The custom nodes, indexed by `Op::Custom::k`.
    pub(crate) fn customs(&self) -> &[Arc<dyn CustomField>] {
        &self.0.customs
    }
    /// True when both tapes are the same shared program (no copy was made).
    pub fn ptr_eq(&self, other: &Tape) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// A shorter tape that gives the same values wherever `choices` hold (on the region the
    /// interval pass that produced them covered).
    ///
    /// A min or max whose choice is `Left` (`Right`) is replaced by its left (right)
    /// operand, everything no longer needed by the output is dropped, and registers are
    /// allocated again. With no choice decided, the tape itself is returned (a pointer
    /// copy). `choices` shorter than [`Tape::choice_count`] count as `Both` for the
    /// missing ones.
    pub fn simplify(&self, choices: &[Choice]) -> Tape {
        if !choices.iter().any(|c| *c != Choice::Both) {
            return self.clone();
        }
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut s) => self.simplify_with(choices, &mut s),
            // Re-entered from a custom field's callback on this thread: use fresh buffers.
            Err(_) => self.simplify_with(choices, &mut Scratch::default()),
        })
    }

    /// The tape narrowed to the box of `ev`'s last pass over it: [`Tape::simplify`] by that
    /// pass's choices, and each custom node it met replaced by what the node's
    /// [`CustomField::narrow`] gives for its input box there. Equal to `self` everywhere
    /// in the box; `self` itself (a pointer copy) when nothing narrowed.
    pub fn narrow(&self, ev: &crate::IntervalEval) -> Tape {
        let short = self.simplify(ev.choices());
        let mut narrowed: Option<Vec<Arc<dyn CustomField>>> = None;
        for &(k, b) in ev.custom_boxes() {
            let Some(node) = self.0.customs.get(k as usize) else {
                continue;
            };
            if let Some(n) = node.narrow(b) {
                narrowed.get_or_insert_with(|| self.0.customs.to_vec())[k as usize] = n;
            }
        }
        match narrowed {
            None => short,
            Some(customs) => Tape(Arc::new(TapeData {
                ops: short.0.ops.clone(),
                regs: short.0.regs,
                choices: short.0.choices,
                out: short.0.out,
                customs: customs.into(),
            })),
        }
    }

    fn simplify_with(&self, choices: &[Choice], s: &mut Scratch) -> Tape {
        const NONE: u32 = u32::MAX;
        let old = &self.0.ops;
        // new_of[r]: the new register that old register r's current value goes to, or
        // NONE when no live instruction needs it (walking backwards).
        s.new_of.clear();
        s.new_of.resize(self.0.regs, NONE);
        s.free.clear();
        s.ops.clear();
        let mut count = 1u32;
        s.new_of[self.0.out as usize] = 0;
        let mut k = self.0.choices;
        for op in old.iter().rev() {
            let choice = if op.is_choice() {
                k -= 1;
                choices.get(k).copied().unwrap_or(Choice::Both)
            } else {
                Choice::Both
            };
            let out = op_out(op);
            let r = s.new_of[out as usize];
            if r == NONE {
                continue; // nothing live reads this value
            }
            // The value dies here (walking backwards): its register is free above.
            s.new_of[out as usize] = NONE;
            // A decided choice becomes its kept operand: a register or an immediate.
            let kept = match (choice, *op) {
                (Choice::Left, Op::Binary { a, .. } | Op::BinaryRI { a, .. }) => Some(Ok(a)),
                (Choice::Right, Op::Binary { b, .. } | Op::BinaryIR { b, .. }) => Some(Ok(b)),
                (Choice::Left, Op::BinaryIR { imm, .. }) => Some(Err(imm)),
                (Choice::Right, Op::BinaryRI { imm, .. }) => Some(Err(imm)),
                _ => None,
            };
            match kept {
                Some(Ok(a)) => {
                    let na = s.new_of[a as usize];
                    if na == NONE {
                        // The operand's value goes straight to where the result went.
                        s.new_of[a as usize] = r;
                    } else {
                        s.ops.push(Op::Copy { out: r, a: na });
                        s.free.push(r);
                    }
                    continue;
                }
                Some(Err(c)) => {
                    s.ops.push(Op::Const { out: r, c });
                    s.free.push(r);
                    continue;
                }
                None => {}
            }
            let (new_of, free) = (&mut s.new_of, &mut s.free);
            let mut reg = |a: u32| {
                let a = a as usize;
                if new_of[a] == NONE {
                    new_of[a] = free.pop().unwrap_or_else(|| {
                        count += 1;
                        count - 1
                    });
                }
                new_of[a]
            };
            let new = match *op {
                Op::Var { v, .. } => Op::Var { out: r, v },
                Op::Const { c, .. } => Op::Const { out: r, c },
                Op::Unary { op, a, .. } => Op::Unary {
                    op,
                    out: r,
                    a: reg(a),
                },
                Op::Binary { op, a, b, .. } => {
                    let a = reg(a);
                    Op::Binary {
                        op,
                        out: r,
                        a,
                        b: reg(b),
                    }
                }
                Op::BinaryRI { op, a, imm, .. } => Op::BinaryRI {
                    op,
                    out: r,
                    a: reg(a),
                    imm,
                },
                Op::BinaryIR { op, imm, b, .. } => Op::BinaryIR {
                    op,
                    out: r,
                    imm,
                    b: reg(b),
                },
                Op::Custom { k, args, .. } => {
                    let args = [reg(args[0]), reg(args[1]), reg(args[2])];
                    Op::Custom { k, out: r, args }
                }
                Op::Copy { a, .. } => Op::Copy { out: r, a: reg(a) },
            };
            s.free.push(r);
            s.ops.push(new);
        }
        let ops: Vec<Op> = s.ops.iter().rev().copied().collect();
        Tape::from_ops(ops, count as usize, self.0.customs.clone())
    }
}

/// Reusable buffers for [`Tape::simplify`].
#[derive(Default)]
struct Scratch {
    new_of: Vec<u32>,
    free: Vec<u32>,
    ops: Vec<Op>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

fn op_out(op: &Op) -> u32 {
    match *op {
        Op::Var { out, .. }
        | Op::Const { out, .. }
        | Op::Unary { out, .. }
        | Op::Binary { out, .. }
        | Op::BinaryRI { out, .. }
        | Op::BinaryIR { out, .. }
        | Op::Custom { out, .. }
        | Op::Copy { out, .. } => out,
    }
}

/// Linear-scan register allocation from the output backwards: a value gets a register at
/// its last use (the first seen walking backwards) and gives it back at its definition.
/// Operands are assigned before the result's register is released, so an instruction
/// never writes a register it reads.
fn allocate(ssa: &[Ssa]) -> (Vec<Op>, usize) {
    let n = ssa.len();
    let mut reg_of = vec![u32::MAX; n];
    let mut free: Vec<u32> = Vec::new();
    let mut count = 0u32;
    let mut ops = Vec::with_capacity(n);
    if n == 0 {
        return (ops, 1);
    }
    reg_of[n - 1] = 0;
    count = count.max(1);
    let take = |free: &mut Vec<u32>, count: &mut u32| match free.pop() {
        Some(r) => r,
        None => {
            *count += 1;
            *count - 1
        }
    };
    for i in (0..n).rev() {
        let out = reg_of[i];
        let out = if out == u32::MAX {
            // Dead value (cannot happen for tapes built here); give it a scratch register.
            take(&mut free, &mut count)
        } else {
            out
        };
        let mut r = |a: u32| {
            let a = a as usize;
            if reg_of[a] == u32::MAX {
                reg_of[a] = take(&mut free, &mut count);
            }
            reg_of[a]
        };
        let op = match ssa[i] {
            Ssa::Var(v) => Op::Var { out, v },
            Ssa::Const(c) => Op::Const { out, c },
            Ssa::Unary(op, a) => Op::Unary { op, out, a: r(a) },
            Ssa::Binary(op, a, b) => {
                let a = r(a);
                let b = r(b);
                Op::Binary { op, out, a, b }
            }
            Ssa::BinaryRI(op, a, imm) => Op::BinaryRI {
                op,
                out,
                a: r(a),
                imm,
            },
            Ssa::BinaryIR(op, imm, b) => Op::BinaryIR {
                op,
                out,
                imm,
                b: r(b),
            },
            Ssa::Custom(k, ins) => {
                let args = [r(ins[0]), r(ins[1]), r(ins[2])];
                Op::Custom { k, out, args }
            }
        };
        free.push(out);
        ops.push(op);
    }
    ops.reverse();
    (ops, count as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Interval, IntervalEval};

    /// Every instruction writes a register in range that none of its operands use (the
    /// batch evaluator borrows the output mutably next to shared operands).
    fn check_invariants(t: &Tape) {
        for op in t.ops() {
            let out = op_out(op);
            assert!((out as usize) < t.register_count());
            let args: Vec<u32> = match *op {
                Op::Var { .. } | Op::Const { .. } => vec![],
                Op::Unary { a, .. } | Op::BinaryRI { a, .. } | Op::Copy { a, .. } => vec![a],
                Op::BinaryIR { b, .. } => vec![b],
                Op::Binary { a, b, .. } => vec![a, b],
                Op::Custom { args, .. } => args.to_vec(),
            };
            for a in args {
                assert!((a as usize) < t.register_count());
                assert_ne!(a, out, "{op:?} writes a register it reads");
            }
        }
        assert_eq!(t.output(), 0);
        assert_eq!(
            t.ops().iter().filter(|o| o.is_choice()).count(),
            t.choice_count()
        );
    }

    #[test]
    fn simplified_colonnade_tapes_keep_register_invariants() {
        let text = include_str!("../../../fixtures/vm/colonnade.vm");
        let tape = Tape::new(&crate::vm::parse_vm(text).expect("parses"));
        check_invariants(&tape);
        let mut ie = IntervalEval::new();
        let mut shortest = tape.len();
        for i in 0..200 {
            let side = [2.0, 0.5, 0.125, 1.0 / 32.0][i % 4];
            let corner = [0, 1, 2].map(|k| ((i * [31, 57, 93][k]) % 64) as f64 / 32.0 - 1.0);
            let b = corner.map(|c| Interval::try_from((c, c + side)).expect("box"));
            ie.eval(&tape, b);
            let short = tape.simplify(ie.choices());
            check_invariants(&short);
            ie.eval(&short, b);
            let shorter = short.simplify(ie.choices());
            check_invariants(&shorter);
            shortest = shortest.min(shorter.len());
        }
        assert!(
            shortest < tape.len() / 10,
            "simplification barely shrank: {shortest}"
        );
    }
}
