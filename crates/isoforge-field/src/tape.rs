//! Tapes: a graph flattened to SSA instructions with allocated registers, and their
//! simplification by the choices an interval pass recorded.
//!
//! A tape keeps two forms of the same program, instruction for instruction:
//! - SSA form (`ssa`): instruction `i` defines value `i`, operands name earlier values.
//!   Simplification works on this form.
//! - Register form (`ops`): the same instructions with operands and results in a small set
//!   of reusable registers, allocated by a linear scan from the output backwards (as
//!   fidget does). Evaluators run this form; few registers keep the batch evaluator's
//!   working set in cache.
//!
//! Constant operands of binary operations are immediates, so `x * 2` is one instruction.

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

impl Ssa {
    /// Calls `f` on every operand.
    fn for_args(&self, mut f: impl FnMut(u32)) {
        match *self {
            Ssa::Var(_) | Ssa::Const(_) => {}
            Ssa::Unary(_, a) | Ssa::BinaryRI(_, a, _) | Ssa::BinaryIR(_, _, a) => f(a),
            Ssa::Binary(_, a, b) => {
                f(a);
                f(b)
            }
            Ssa::Custom(_, i) => i.iter().for_each(|&a| f(a)),
        }
    }
    /// The same instruction with every operand mapped through `f`.
    fn map_args(&self, mut f: impl FnMut(u32) -> u32) -> Ssa {
        match *self {
            Ssa::Var(v) => Ssa::Var(v),
            Ssa::Const(c) => Ssa::Const(c),
            Ssa::Unary(op, a) => Ssa::Unary(op, f(a)),
            Ssa::Binary(op, a, b) => Ssa::Binary(op, f(a), f(b)),
            Ssa::BinaryRI(op, a, c) => Ssa::BinaryRI(op, f(a), c),
            Ssa::BinaryIR(op, c, a) => Ssa::BinaryIR(op, c, f(a)),
            Ssa::Custom(k, i) => Ssa::Custom(k, i.map(f)),
        }
    }
    fn is_choice(&self) -> bool {
        matches!(
            self,
            Ssa::Binary(BinaryOp::Min | BinaryOp::Max, ..)
                | Ssa::BinaryRI(BinaryOp::Min | BinaryOp::Max, ..)
                | Ssa::BinaryIR(BinaryOp::Min | BinaryOp::Max, ..)
        )
    }
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
}

struct TapeData {
    ssa: Vec<Ssa>,
    ops: Vec<Op>,
    regs: usize,
    choices: usize,
    /// The register holding the result after the last instruction.
    out: u32,
    customs: Vec<Arc<dyn CustomField>>,
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
        Tape::from_ssa(ssa, customs)
    }

    /// Builds the register form of an SSA program whose last instruction is the output
    /// and whose every instruction is live.
    fn from_ssa(ssa: Vec<Ssa>, customs: Vec<Arc<dyn CustomField>>) -> Tape {
        let (ops, regs) = allocate(&ssa);
        let choices = ssa.iter().filter(|s| s.is_choice()).count();
        let out = match ops.last() {
            Some(op) => op_out(op),
            None => 0,
        };
        Tape(Arc::new(TapeData {
            ssa,
            ops,
            regs,
            choices,
            out,
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
    /// operand, then everything no longer reachable from the output is dropped and
    /// registers are allocated again. With no choice decided, the tape itself is returned
    /// (a pointer copy). `choices` shorter than [`Tape::choice_count`] count as `Both`
    /// for the missing ones.
    pub fn simplify(&self, choices: &[Choice]) -> Tape {
        if !choices.iter().any(|c| *c != Choice::Both) {
            return self.clone();
        }
        let ssa = &self.0.ssa;
        let n = ssa.len();
        // Forward: where each value really comes from once decided choices are applied.
        // `alias[i] = j` means value i equals value j; u32::MAX marks an immediate that
        // replaced it (stored in `imm`).
        let mut alias: Vec<u32> = Vec::with_capacity(n);
        let mut imm: Vec<f64> = vec![0.0; n];
        let mut k = 0;
        for (i, op) in ssa.iter().enumerate() {
            let mut target = i as u32;
            if op.is_choice() {
                let c = choices.get(k).copied().unwrap_or(Choice::Both);
                k += 1;
                match (c, *op) {
                    (Choice::Left, Ssa::Binary(_, a, _) | Ssa::BinaryRI(_, a, _)) => {
                        target = alias[a as usize];
                        imm[i] = imm[a as usize];
                    }
                    (Choice::Right, Ssa::Binary(_, _, b) | Ssa::BinaryIR(_, _, b)) => {
                        target = alias[b as usize];
                        imm[i] = imm[b as usize];
                    }
                    (Choice::Right, Ssa::BinaryRI(_, _, c))
                    | (Choice::Left, Ssa::BinaryIR(_, c, _)) => {
                        target = u32::MAX;
                        imm[i] = c;
                    }
                    _ => {}
                }
            }
            alias.push(target);
        }
        // Backward: liveness from the output, through aliases.
        let mut live = vec![false; n];
        let root = alias[n - 1];
        if root == u32::MAX {
            return Tape::from_ssa(vec![Ssa::Const(imm[n - 1])], Vec::new());
        }
        live[root as usize] = true;
        for i in (0..n).rev() {
            if !live[i] {
                continue;
            }
            ssa[i].for_args(|a| {
                let t = alias[a as usize];
                if t != u32::MAX {
                    live[t as usize] = true;
                }
            });
        }
        // Emit live instructions with renumbered operands. An operand aliased to an
        // immediate turns a register operand into an immediate one.
        let mut renum = vec![u32::MAX; n];
        let mut out: Vec<Ssa> = Vec::with_capacity(n);
        let mut used_customs: Vec<u32> = Vec::new();
        let mut customs: Vec<Arc<dyn CustomField>> = Vec::new();
        let mut const_slot: Vec<(u64, u32)> = Vec::new();
        for i in 0..n {
            if !live[i] {
                continue;
            }
            let op = ssa[i];
            let imm_of = |a: u32| (alias[a as usize] == u32::MAX).then(|| imm[a as usize]);
            let reg = |a: u32| renum[alias[a as usize] as usize];
            let new = match op {
                Ssa::Binary(bop, a, b) => match (imm_of(a), imm_of(b)) {
                    (None, None) => Ssa::Binary(bop, reg(a), reg(b)),
                    (None, Some(c)) => Ssa::BinaryRI(bop, reg(a), c),
                    (Some(c), None) => Ssa::BinaryIR(bop, c, reg(b)),
                    (Some(x), Some(y)) => Ssa::Const(crate::eval::scalar::binary(bop, x, y)),
                },
                Ssa::BinaryRI(bop, a, c) => match imm_of(a) {
                    None => Ssa::BinaryRI(bop, reg(a), c),
                    Some(x) => Ssa::Const(crate::eval::scalar::binary(bop, x, c)),
                },
                Ssa::BinaryIR(bop, c, b) => match imm_of(b) {
                    None => Ssa::BinaryIR(bop, c, reg(b)),
                    Some(y) => Ssa::Const(crate::eval::scalar::binary(bop, c, y)),
                },
                Ssa::Unary(uop, a) => match imm_of(a) {
                    None => Ssa::Unary(uop, reg(a)),
                    Some(x) => Ssa::Const(crate::eval::scalar::unary(uop, x)),
                },
                Ssa::Custom(kk, ins) => {
                    // Immediate operands of a custom node need a constant instruction.
                    let mut args = [0u32; 3];
                    for (j, &a) in ins.iter().enumerate() {
                        args[j] = match imm_of(a) {
                            None => reg(a),
                            Some(c) => {
                                let bits = c.to_bits();
                                match const_slot.iter().find(|(b, _)| *b == bits) {
                                    Some((_, s)) => *s,
                                    None => {
                                        let s = out.len() as u32;
                                        out.push(Ssa::Const(c));
                                        const_slot.push((bits, s));
                                        s
                                    }
                                }
                            }
                        };
                    }
                    let slot = match used_customs.iter().position(|&u| u == kk) {
                        Some(p) => p as u32,
                        None => {
                            used_customs.push(kk);
                            customs.push(self.0.customs[kk as usize].clone());
                            customs.len() as u32 - 1
                        }
                    };
                    Ssa::Custom(slot, args)
                }
                other => other.map_args(reg),
            };
            renum[i] = out.len() as u32;
            out.push(new);
        }
        // The root is the highest live value and constants for custom nodes are emitted
        // just before their user, so the root is still the last instruction.
        debug_assert_eq!(renum[root as usize] as usize, out.len() - 1);
        Tape::from_ssa(out, customs)
    }
}

fn op_out(op: &Op) -> u32 {
    match *op {
        Op::Var { out, .. }
        | Op::Const { out, .. }
        | Op::Unary { out, .. }
        | Op::Binary { out, .. }
        | Op::BinaryRI { out, .. }
        | Op::BinaryIR { out, .. }
        | Op::Custom { out, .. } => out,
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
