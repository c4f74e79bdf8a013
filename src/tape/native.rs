//! A program's `f64` passes compiled to machine code (Cranelift), for runs that evaluate one
//! program many times.
//!
//! The interpreter of [`Tape::forward`] spends most of an operation on reading the operation,
//! its lane range and its operands' rows; compiled, each operation is a few loads, the
//! arithmetic and stores at offsets fixed when the program and its seeding were made. The
//! governor's exact evaluation takes 2.0 instead of 4.3 µs and its residual 0.3 instead of
//! 1.3 µs, the 12-arm governor's 25 and 2.4 instead of 39 and 8.5 µs; compiling takes
//! 10–400 ms, so a [`Program`](crate::program::Program) compiles its
//! passes only after many evaluations (a Monte Carlo run, a quadrature, a long sweep).
//!
//! The compiled code does exactly what the interpreter does, operation by operation and lane by
//! lane: the same `f64` operations on the same operands in the same order (Cranelift neither
//! reassociates nor contracts floating-point arithmetic), the lanes of every chunk the
//! interpreter writes (zeros where it reads a row's unwritten lanes), and the division and the
//! elementary functions through the interpreter's own code. Its results are therefore the
//! interpreter's to the bit, so when a run switches to it does not change what the run
//! computes (`tests/native.rs`). Only row-per-operation passes of at most
//! `MOST_LANE_WORK` lane operations are compiled: a big program's passes share tangent rows
//! (not compiled here), and its code would be many megabytes and take seconds to compile.
//!
//! Cranelift: <https://cranelift.dev>, the code generator of Wasmtime.

use super::seeding::{CHUNK, Mark};
use super::{Op, Seeding, Tape, Term};
use cranelift_codegen::ir::{
    AbiParam, InstBuilder, MemFlagsData, StackSlotData, StackSlotKind, UserFuncName, Value, types,
};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{Linkage, Module, default_libcall_names};

/// Programs with more lane operations than this are not compiled (the code would be larger
/// than the caches that make it fast, and its compilation long).
const MOST_LANE_WORK: usize = 200_000;

/// The compiled code's signature: operation values, tangent rows, inputs, the operations
/// (for the callbacks).
type Code = unsafe extern "C" fn(*mut f64, *mut f64, *const f64, *const Op);

/// One compiled pass of one program (see the module documentation).
pub struct NativePass {
    /// Owns the code; freed when the pass is dropped.
    module: Option<JITModule>,
    code: Code,
    /// The program's length and the number of inputs the code reads.
    ops: usize,
    inputs: usize,
    /// The seeding compiled for (`None`: values only) and its row stride.
    seeding: Option<Mark>,
    stride: usize,
}

// SAFETY: the code is immutable once finalised and keeps no state: every call works on the
// buffers passed to it. The module is only touched again when the pass is dropped.
unsafe impl Send for NativePass {}
unsafe impl Sync for NativePass {}

impl Drop for NativePass {
    fn drop(&mut self) {
        if let Some(module) = self.module.take() {
            // SAFETY: the only pointer into the code is `self.code`, dropped with `self`.
            unsafe { module.free_memory() };
        }
    }
}

impl std::fmt::Debug for NativePass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NativePass")
            .field("ops", &self.ops)
            .field("seeding", &self.seeding)
            .finish_non_exhaustive()
    }
}

/// Value and local partial derivatives of operation `i` (division and the functions), as the
/// interpreter computes them: `out = [value, ∂/∂a, ∂/∂b]`. Called by the compiled code only.
///
/// # Safety
///
/// `ops` points to at least `i + 1` operations, `val` to the `i` values of the operations
/// before `i`, and `out` to three writable numbers that alias neither (the compiled code
/// passes its program's operations, its value row and a stack slot of its own).
unsafe extern "C" fn partials(ops: *const Op, i: usize, val: *const f64, out: *mut f64) {
    // SAFETY: the caller's contract above.
    let (op, val, out) = unsafe {
        (
            *ops.add(i),
            std::slice::from_raw_parts(val, i),
            std::slice::from_raw_parts_mut(out, 3),
        )
    };
    let (v, da, db) = op.partials(val);
    out[0] = v;
    out[1] = da.unwrap_or(0.0);
    out[2] = db.unwrap_or(0.0);
}

/// Value of operation `i` as [`Tape::eval`] computes it (the operations not compiled inline).
/// Called by the compiled code only.
///
/// # Safety
///
/// `ops` points to at least `i + 1` operations and `val` to the `i` values of the operations
/// before `i`, as for [`partials`].
unsafe extern "C" fn value(ops: *const Op, i: usize, val: *const f64) -> f64 {
    // SAFETY: the caller's contract above.
    let (op, val) = unsafe { (*ops.add(i), std::slice::from_raw_parts(val, i)) };
    op.eval(val)
}

/// Lanes an operation of [`Tape::forward`] writes in a row-per-operation pass: none, its one
/// lane, or whole chunks from its first lane.
fn written((lo, w): (u32, u32)) -> std::ops::Range<usize> {
    let lo = lo as usize;
    match w as usize {
        0 => 0..0,
        1 => lo..lo + 1,
        w => lo..lo + w.div_ceil(CHUNK) * CHUNK,
    }
}

impl Tape {
    /// [`Tape::forward`] over `f64` with `seeding` compiled, or `None` where it is not
    /// compiled: shared rows or blocks of lanes, seeds at rates other than one, too large a
    /// program, or a host Cranelift does not generate code for.
    pub fn compile_forward(&self, seeding: &Seeding) -> Option<NativePass> {
        let lane_work: usize = seeding.range.iter().map(|&r| written(r).len()).sum();
        if seeding.slots.reuse
            || !seeding.blocks.is_empty()
            || !seeding.input_weights.is_empty()
            || lane_work > MOST_LANE_WORK
        {
            return None;
        }
        self.compile(Some(seeding))
    }

    /// [`Tape::eval`] over `f64` compiled (`None` as for [`Tape::compile_forward`]).
    pub fn compile_eval(&self) -> Option<NativePass> {
        (self.ops.len() <= MOST_LANE_WORK).then(|| self.compile(None))?
    }

    /// The pass compiled, or `None` where Cranelift reports an error; should it panic all
    /// the same, `None` too (the run goes on interpreted).
    fn compile(&self, seeding: Option<&Seeding>) -> Option<NativePass> {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.emit(seeding)))
            .ok()
            .flatten()
    }

    /// [`Tape::compile`]'s work.
    fn emit(&self, seeding: Option<&Seeding>) -> Option<NativePass> {
        let stride = seeding.map_or(0, |s| s.lanes + CHUNK - 1);
        // Every offset is an `i32` of bytes.
        let bytes = (self.ops.len() + 1) * (stride + 1) * 8;
        if bytes > i32::MAX as usize {
            return None;
        }
        let mut flags = settings::builder();
        flags.set("opt_level", "speed").ok()?;
        flags.set("is_pic", "false").ok()?;
        flags.set("use_colocated_libcalls", "false").ok()?;
        let isa = cranelift_native::builder()
            .ok()?
            .finish(settings::Flags::new(flags))
            .ok()?;
        let mut jit = JITBuilder::with_isa(isa, default_libcall_names());
        jit.symbol("modaltol_partials", partials as *const u8);
        jit.symbol("modaltol_value", value as *const u8);
        let mut module = JITModule::new(jit);
        let ptr = module.target_config().pointer_type();
        let mut ctx = module.make_context();
        ctx.func.signature.params = vec![AbiParam::new(ptr); 4];
        let mut partials_sig = module.make_signature();
        partials_sig.params = vec![AbiParam::new(ptr); 4];
        let mut value_sig = module.make_signature();
        value_sig.params = vec![AbiParam::new(ptr); 3];
        value_sig.returns = vec![AbiParam::new(types::F64)];
        let partials_id = module
            .declare_function("modaltol_partials", Linkage::Import, &partials_sig)
            .ok()?;
        let value_id = module
            .declare_function("modaltol_value", Linkage::Import, &value_sig)
            .ok()?;
        let id = module
            .declare_function("pass", Linkage::Local, &ctx.func.signature)
            .ok()?;
        ctx.func.name = UserFuncName::user(0, id.as_u32());
        let mut fctx = FunctionBuilderContext::new();
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fctx);
        let callbacks = (
            module.declare_func_in_func(partials_id, b.func),
            module.declare_func_in_func(value_id, b.func),
        );
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        let args = b.block_params(block).to_vec();
        let mut e = Emitter {
            b,
            val: args[0],
            tan: args[1],
            x: args[2],
            ops: args[3],
            ptr,
            stride,
            slot: None,
            callbacks,
        };
        for (i, op) in self.ops.iter().enumerate().skip(self.n_static) {
            let v = match seeding {
                Some(s) => e.forward(i, *op, s),
                None => e.value(i, *op),
            };
            e.store(e.val, i, v);
        }
        e.b.ins().return_(&[]);
        e.b.seal_all_blocks();
        e.b.finalize(module.target_config());
        module.define_function(id, &mut ctx).ok()?;
        module.clear_context(&mut ctx);
        module.finalize_definitions().ok()?;
        let code = module.get_finalized_function(id);
        // SAFETY: `code` is the function just defined with the signature `Code`.
        let code = unsafe { std::mem::transmute::<*const u8, Code>(code) };
        let inputs = self.ops.iter().fold(0, |n, op| match *op {
            Op::Input(k) => n.max(k as usize + 1),
            _ => n,
        });
        Some(NativePass {
            module: Some(module),
            code,
            ops: self.ops.len(),
            inputs,
            seeding: seeding.map(|s| s.id.mark()),
            stride,
        })
    }

    /// [`Tape::forward_rows`] over `f64` through `pass`, compiled by [`Tape::compile_forward`] from
    /// this program and `seeding`: the same results to the bit.
    pub fn forward_native<'w>(
        &self,
        pass: &NativePass,
        fixed: &[f64],
        x: &[f64],
        seeding: &Seeding,
        work: &'w mut super::Forward<f64>,
    ) -> (Vec<f64>, super::Rows<'w, f64>) {
        assert!(
            pass.ops == self.ops.len()
                && pass.seeding.as_ref().is_some_and(|m| m.is(&seeding.id))
                && x.len() >= pass.inputs
                && fixed.len() >= self.n_static,
            "a compiled pass runs on its own program, seeding and inputs"
        );
        let rows = seeding.slots.rows + 1;
        work.val.clear();
        work.val.resize(self.ops.len(), 0.0);
        work.val[..self.n_static].copy_from_slice(&fixed[..self.n_static]);
        if !work.seeding.is(&seeding.id) || work.tan.len() != rows * pass.stride {
            work.tan.clear();
            work.tan.resize(rows * pass.stride, 0.0);
            work.seeding = seeding.id.mark();
        }
        // SAFETY: the code reads and writes `val` below the program's length, `tan` below
        // `rows · stride` (the offsets of a row-per-operation seeding) and `x` below `inputs`,
        // as the assertion and the sizes above ensure.
        unsafe {
            (pass.code)(
                work.val.as_mut_ptr(),
                work.tan.as_mut_ptr(),
                x.as_ptr(),
                self.ops.as_ptr(),
            );
        }
        let (values, rows) = self.read_outputs(&work.val, &work.tan, seeding, pass.stride);
        (values, rows.unpacked(seeding))
    }

    /// [`Tape::eval`] over `f64` through `pass` (from [`Tape::compile_eval`] on this program).
    pub fn eval_native(
        &self,
        pass: &NativePass,
        fixed: &[f64],
        x: &[f64],
        work: &mut Vec<f64>,
    ) -> Vec<f64> {
        assert!(
            pass.ops == self.ops.len()
                && pass.seeding.is_none()
                && x.len() >= pass.inputs
                && fixed.len() >= self.n_static,
            "a compiled pass runs on its own program and inputs"
        );
        work.clear();
        work.resize(self.ops.len(), 0.0);
        work[..self.n_static].copy_from_slice(&fixed[..self.n_static]);
        // SAFETY: values-only code reads and writes `work` below the program's length and
        // reads `x` below `inputs`; it has no tangent rows.
        unsafe {
            (pass.code)(
                work.as_mut_ptr(),
                std::ptr::null_mut(),
                x.as_ptr(),
                self.ops.as_ptr(),
            );
        }
        self.outputs
            .iter()
            .map(|o| match o.term() {
                Term::Const(c) => c,
                Term::Node(i, _) => work[i as usize],
            })
            .collect()
    }
}

/// Emits one pass into a single block.
struct Emitter<'a> {
    b: FunctionBuilder<'a>,
    val: Value,
    tan: Value,
    x: Value,
    ops: Value,
    ptr: types::Type,
    stride: usize,
    /// Three numbers on the stack for [`partials`].
    slot: Option<cranelift_codegen::ir::StackSlot>,
    callbacks: (
        cranelift_codegen::ir::FuncRef,
        cranelift_codegen::ir::FuncRef,
    ),
}

impl Emitter<'_> {
    fn load(&mut self, base: Value, index: usize) -> Value {
        let flags = MemFlagsData::trusted();
        self.b
            .ins()
            .load(types::F64, flags, base, (index * 8) as i32)
    }

    fn store(&mut self, base: Value, index: usize, v: Value) {
        let flags = MemFlagsData::trusted();
        self.b.ins().store(flags, v, base, (index * 8) as i32);
    }

    fn constant(&mut self, c: f64) -> Value {
        self.b.ins().f64const(c)
    }

    /// Value of operation `i` as [`Tape::eval`] computes it.
    fn value(&mut self, i: usize, op: Op) -> Value {
        let ins = |e: &mut Self, a: u32| e.load(e.val, a as usize);
        match op {
            Op::Input(k) => self.load(self.x, k as usize),
            Op::Const(c) => self.constant(c),
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) => {
                let (a, b) = (ins(self, a), ins(self, b));
                match op {
                    Op::Add(..) => self.b.ins().fadd(a, b),
                    Op::Sub(..) => self.b.ins().fsub(a, b),
                    _ => self.b.ins().fmul(a, b),
                }
            }
            Op::Neg(a) => {
                let a = ins(self, a);
                self.b.ins().fneg(a)
            }
            Op::AddC(a, c) | Op::MulC(a, c) => {
                let (a, c) = (ins(self, a), self.constant(c));
                match op {
                    Op::AddC(..) => self.b.ins().fadd(a, c),
                    _ => self.b.ins().fmul(a, c),
                }
            }
            Op::MulAdd(a, b, c) | Op::MulSub(a, b, c) | Op::SubMul(a, b, c) => {
                let (a, b, c) = (ins(self, a), ins(self, b), ins(self, c));
                let p = self.b.ins().fmul(a, b);
                match op {
                    Op::MulAdd(..) => self.b.ins().fadd(p, c),
                    Op::MulSub(..) => self.b.ins().fsub(p, c),
                    _ => self.b.ins().fsub(c, p),
                }
            }
            _ => {
                let index = self.b.ins().iconst(self.ptr, i as i64);
                let call = self
                    .b
                    .ins()
                    .call(self.callbacks.1, &[self.ops, index, self.val]);
                self.b.inst_results(call)[0]
            }
        }
    }

    /// Operation `i` of [`Tape::forward`]: its lanes written, its value returned.
    fn forward(&mut self, i: usize, op: Op, s: &Seeding) -> Value {
        let lanes = written(s.range[i]);
        match op {
            Op::Input(k) => {
                for l in lanes.clone() {
                    let z = self.constant(0.0);
                    self.store(self.tan, i * self.stride + l, z);
                }
                if !lanes.is_empty() {
                    let one = self.constant(1.0);
                    for &l in s.input_lanes.get(k as usize).map_or(&[][..], |v| &v[..]) {
                        self.store(self.tan, i * self.stride + l as usize, one);
                    }
                }
                self.load(self.x, k as usize)
            }
            Op::Const(c) => {
                for l in lanes {
                    let z = self.constant(0.0);
                    self.store(self.tan, i * self.stride + l, z);
                }
                self.constant(c)
            }
            Op::Add(a, b) | Op::Sub(a, b) => {
                for l in lanes {
                    let (x, y) = (self.lane(s, a, l), self.lane(s, b, l));
                    let t = match op {
                        Op::Add(..) => self.b.ins().fadd(x, y),
                        _ => self.b.ins().fsub(x, y),
                    };
                    self.store(self.tan, i * self.stride + l, t);
                }
                self.value(i, op)
            }
            Op::Neg(a) | Op::AddC(a, _) | Op::MulC(a, _) => {
                for l in lanes {
                    let x = self.lane(s, a, l);
                    let t = match op {
                        Op::Neg(_) => self.b.ins().fneg(x),
                        Op::AddC(..) => x,
                        Op::MulC(_, c) => {
                            let c = self.constant(c);
                            self.b.ins().fmul(x, c)
                        }
                        _ => unreachable!("one of the three matched"),
                    };
                    self.store(self.tan, i * self.stride + l, t);
                }
                self.value(i, op)
            }
            Op::Mul(..) | Op::MulAdd(..) | Op::MulSub(..) | Op::SubMul(..) => {
                self.product(i, op, s)
            }
            _ => self.by_callback(i, op, s),
        }
    }

    /// Operand `a`'s lane `l`: a zero outside the lanes its operation wrote.
    fn lane(&mut self, s: &Seeding, a: u32, l: usize) -> Value {
        if written(s.range[a as usize]).contains(&l) {
            self.load(self.tan, a as usize * self.stride + l)
        } else {
            self.constant(0.0)
        }
    }

    /// Operand `a`'s value.
    fn v(&mut self, a: u32) -> Value {
        self.load(self.val, a as usize)
    }

    /// [`Self::forward`] of a product (`Mul`, `MulAdd`, `MulSub`, `SubMul`).
    fn product(&mut self, i: usize, op: Op, s: &Seeding) -> Value {
        let lanes = written(s.range[i]);
        let [Some(a), Some(b), _] = op.args() else {
            unreachable!("a product has two factors")
        };
        let (va, vb) = (self.v(a), self.v(b));
        for l in lanes {
            let (x, y) = (self.lane(s, a, l), self.lane(s, b, l));
            let xb = self.b.ins().fmul(x, vb);
            let ay = self.b.ins().fmul(va, y);
            let d = self.b.ins().fadd(xb, ay);
            let t = match op {
                Op::MulAdd(_, _, c) => {
                    let z = self.lane(s, c, l);
                    self.b.ins().fadd(d, z)
                }
                Op::MulSub(_, _, c) => {
                    let z = self.lane(s, c, l);
                    self.b.ins().fsub(d, z)
                }
                Op::SubMul(_, _, c) => {
                    let z = self.lane(s, c, l);
                    self.b.ins().fsub(z, d)
                }
                _ => d,
            };
            self.store(self.tan, i * self.stride + l, t);
        }
        let p = self.b.ins().fmul(va, vb);
        match op {
            Op::MulAdd(_, _, c) => {
                let c = self.v(c);
                self.b.ins().fadd(p, c)
            }
            Op::MulSub(_, _, c) => {
                let c = self.v(c);
                self.b.ins().fsub(p, c)
            }
            Op::SubMul(_, _, c) => {
                let c = self.v(c);
                self.b.ins().fsub(c, p)
            }
            _ => p,
        }
    }

    /// [`Self::forward`] of a division or a function: value and partials from the
    /// interpreter's code.
    fn by_callback(&mut self, i: usize, op: Op, s: &Seeding) -> Value {
        let lanes = written(s.range[i]);
        let slot = *self.slot.get_or_insert_with(|| {
            self.b
                .create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, 24, 3))
        });
        let out = self.b.ins().stack_addr(self.ptr, slot, 0);
        let index = self.b.ins().iconst(self.ptr, i as i64);
        self.b
            .ins()
            .call(self.callbacks.0, &[self.ops, index, self.val, out]);
        let [value, da, db] =
            [0, 8, 16].map(|o| self.b.ins().stack_load(self.ptr, types::F64, slot, o));
        let [a, b, _] = op.args();
        for l in lanes {
            let t = match (a, b) {
                (Some(a), Some(b)) => {
                    let (x, y) = (self.lane(s, a, l), self.lane(s, b, l));
                    let dx = self.b.ins().fmul(da, x);
                    let dy = self.b.ins().fmul(db, y);
                    self.b.ins().fadd(dx, dy)
                }
                (Some(a), None) => {
                    let x = self.lane(s, a, l);
                    self.b.ins().fmul(da, x)
                }
                _ => self.constant(0.0),
            };
            self.store(self.tan, i * self.stride + l, t);
        }
        value
    }
}
