//! The passes over a recorded trace that make the programs evaluated: dropping what the kept
//! outputs do not need, fusing products into their sums, placing the operations that depend on
//! fixed inputs only first, and replaying a trace with some inputs made constants.
//!
//! They run once per program, when it is made; the evaluators then run the result many times.

use super::var::record_with;
use super::{Op, Tape, Term, Var};

impl Tape {
    /// The program of the outputs `keep` of a raw trace (in that order): without the
    /// operations they do not need, and with the products used once fused into their sums.
    pub fn finish(&self, keep: &[usize]) -> Tape {
        self.finished(keep, None)
    }

    /// [`Tape::finish`] and then [`Tape::split`] by the inputs `fixed`, in three passes over
    /// the trace instead of one pass each for the pruning, the fusing and the ordering: a
    /// recording makes two programs from a trace of tens of thousands of operations, and each
    /// pass costs a few nanoseconds an operation.
    pub fn finish_split(&self, keep: &[usize], fixed: &[usize]) -> Tape {
        self.finished(keep, Some(fixed))
    }

    /// [`Tape::finish`], split by `fixed` where given.
    ///
    /// Backwards from the outputs, each operation's uses by the live operations are counted;
    /// a product is visited after all its users, so where it has one, a sum or a difference,
    /// that user becomes the fused operation and the product goes (its operands are then the
    /// fused operation's). Forwards, the live operations are renumbered: with `fixed`, those
    /// that depend on the fixed inputs only first, each group in the trace's order. A fused
    /// operation rounds as the two it replaces, so which product a sum of two takes changes
    /// the program's length, never a value.
    fn finished(&self, keep: &[usize], fixed: Option<&[usize]>) -> Tape {
        let n = self.ops.len();
        // Uses by the live operations and the kept outputs (0: not needed), and the last user
        // counted (the only one where there is one; `u32::MAX`: an output).
        let mut uses = vec![0u32; n];
        let mut user = vec![u32::MAX; n];
        for &o in keep {
            if let Term::Node(i, _) = self.outputs[o].term() {
                uses[i as usize] += 1;
            }
        }
        let mut ops = self.ops.clone();
        for i in (0..n).rev() {
            if uses[i] == 0 {
                continue;
            }
            let mut by = i as u32;
            if let Op::Mul(x, y) = ops[i]
                && uses[i] == 1
                && user[i] != u32::MAX
            {
                let u = user[i] as usize;
                let j = i as u32;
                let fused = match ops[u] {
                    Op::Add(a, b) if a == j => Some(Op::MulAdd(x, y, b)),
                    Op::Add(a, b) if b == j => Some(Op::MulAdd(x, y, a)),
                    Op::Sub(a, b) if a == j => Some(Op::MulSub(x, y, b)),
                    Op::Sub(a, b) if b == j => Some(Op::SubMul(x, y, a)),
                    _ => None,
                };
                if let Some(f) = fused {
                    ops[u] = f;
                    uses[i] = 0;
                    by = u as u32;
                }
            }
            let (args, k) = ops[i].operands();
            for &a in &args[..k] {
                uses[a as usize] += 1;
                user[a as usize] = by;
            }
        }
        drop(user);
        // Renumbered: a fixed operation by its place among the fixed ones, the others by
        // theirs among the others, marked, until the number of fixed ones is known.
        const OTHER: u32 = 1 << 31;
        let mut new_index = vec![0u32; n];
        let mut first: Vec<Op> = Vec::with_capacity(n);
        let mut rest: Vec<Op> = Vec::new();
        for i in 0..n {
            if uses[i] == 0 {
                continue;
            }
            let op = ops[i];
            let is_fixed = fixed.is_some_and(|fixed| match op {
                Op::Input(k) => fixed.contains(&(k as usize)),
                op => {
                    let (args, k) = op.operands();
                    args[..k]
                        .iter()
                        .all(|&a| new_index[a as usize] & OTHER == 0)
                }
            });
            let op = op.map(|a| new_index[a as usize]);
            if is_fixed {
                new_index[i] = first.len() as u32;
                first.push(op);
            } else {
                new_index[i] = OTHER | rest.len() as u32;
                rest.push(op);
            }
        }
        let n_static = if fixed.is_some() { first.len() } else { 0 };
        let renumber = |a: u32| {
            if a & OTHER != 0 {
                first.len() as u32 + (a & !OTHER)
            } else {
                a
            }
        };
        let rest: Vec<Op> = rest.into_iter().map(|op| op.map(renumber)).collect();
        let outputs = keep
            .iter()
            .map(|&o| match self.outputs[o].term() {
                Term::Node(i, v) => Var::Node(renumber(new_index[i as usize]), v),
                Term::Const(c) => Var::Const(c),
            })
            .collect();
        first.extend(rest);
        Tape {
            ops: first,
            outputs,
            n_static,
        }
    }

    /// The raw trace of the outputs `keep` with the inputs `constants` (index, value) made
    /// constants: traced again from its own operations at the inputs `x`, so that everything
    /// that folds with those constants folds (`x·0`, `x+0`, ...) as if `f` had been recorded
    /// with them. One recording thus serves several programs: a trace of the mechanics costs
    /// many times its length in hashed operations, a replay one appended operation each. The
    /// replay does not hash-cons: the trace's operations are distinct, and only folding could
    /// make two of them equal (`a·(b+0)` and `a·b`), which would cost a duplicate operation,
    /// never a wrong value (none in the residuals of the shipped examples and the chains of
    /// `scale_chain`; the replay's hashing was 0.6 of the 4.8 ms that recording a 40-segment
    /// chain takes). Only the operations the outputs need are replayed. (`None` where the
    /// replay branched, which a straight-line program does not.)
    pub fn specialise(
        &self,
        x: &[f64],
        constants: &[(usize, f64)],
        keep: &[usize],
    ) -> Option<Tape> {
        let live = self.live(keep);
        record_with(x, false, |v| {
            let mut v = v.to_vec();
            for &(k, c) in constants {
                v[k] = Var::Const(c);
            }
            // Every live operation's operands are live, and written before it.
            let mut work = vec![Var::Const(0.0); self.ops.len()];
            for (i, op) in self.ops.iter().enumerate() {
                if live[i] {
                    work[i] = match *op {
                        Op::Input(k) => v[k as usize],
                        op => op.eval(&work),
                    };
                }
            }
            Some(
                keep.iter()
                    .map(|&o| match self.outputs[o].term() {
                        Term::Node(i, _) => work[i as usize],
                        Term::Const(c) => Var::Const(c),
                    })
                    .collect(),
            )
        })
    }

    /// The operations the outputs `keep` need.
    pub(super) fn live(&self, keep: &[usize]) -> Vec<bool> {
        let mut live = vec![false; self.ops.len()];
        for &o in keep {
            if let Term::Node(i, _) = self.outputs[o].term() {
                live[i as usize] = true;
            }
        }
        for i in (0..self.ops.len()).rev() {
            if live[i] {
                let (args, k) = self.ops[i].operands();
                for &a in &args[..k] {
                    live[a as usize] = true;
                }
            }
        }
        live
    }

    /// The same program with the operations that depend on the inputs `fixed` only (and on
    /// constants) placed first: [`Tape::eval_static`] computes them once, and every later
    /// evaluation at new values of the other inputs starts from there. Topological order is
    /// kept, as static operations never depend on the others.
    pub fn split(&self, fixed: &[usize]) -> Tape {
        self.finished(&(0..self.outputs.len()).collect::<Vec<_>>(), Some(fixed))
    }
}
