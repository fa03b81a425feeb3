//! [`GpuSimulation`]: the TLED step of [`crate::tled::Simulation`] on a wgpu device.
//!
//! Same contract as the CPU simulation: [`GpuSimulation::new`] validates and precomputes
//! (the same [`Discretisation`], the same f64 derived constants rounded once to the
//! stepping precision), [`GpuSimulation::step_many`] advances, and on divergence returns
//! [`Error::Diverged`] naming the step, time and element or node, with the state left as it
//! was before the failing step.
//!
//! One batch of steps is one queue submission with one compute pass: for every step two
//! kernels are dispatched, `element_forces` (which also runs the `saliva_forces` stage on
//! the saliva elements' blocks) and `node_update`. The displacement lives in three buffers
//! used in rotation (`u_s = buf[s % 3]`, `u_{s-1} = buf[(s + 2) % 3]`, `u_{s+1} =
//! buf[(s + 1) % 3]`) and the saliva state in two (read `s % 2`, write `(s + 1) % 2`), so
//! nothing is copied between steps and a failing step leaves the state before it. Only the 16-byte [`Status`] is read back after a
//! batch; the state is read back when asked for ([`GpuSimulation::sync`]).
//!
//! Everything that depends on time only is evaluated in f64 by Rust, once per step of a
//! batch, and uploaded as two short per-step rows, so the CPU's share of a step does not
//! grow with the number of driven nodes (`host/*` in `benches/gpu.rs`):
//!
//! - the step row, in `load_real` (f64 wherever the kernels may use f64): `[1 | the curve
//!   value of every load group at t_s | of every prescribed-displacement curve at t_{s+1} |
//!   the 3x3 matrix of every prescribed rotation at t_{s+1}, row-major]`;
//! - the saliva row, in the stepping scalar: the breaking point `Z` of every saliva element
//!   at `t_s` (eqs. 6-7).
//!
//! Each external load entry is `real(v * row[g])` and each imposed DOF a fixed linear
//! combination of row entries, `real(c_0 row[i_0] + c_1 row[i_1] + ...)` summed left to
//! right in `load_real`, with the terms set up here so that the operations are the CPU's
//! (`solver::apply_constraints_into`). A prescribed DOF is `0 * 1 + v_1 curve_1 + ...`
//! (the CPU's f64 accumulator starts at 0). A rotated DOF `k` is `d_0 R_k0 + d_1 R_k1 +
//! d_2 R_k2 - d_k` (the last term as `(-d_k) * 1`), with `d = x - p` formed in f64 here,
//! as `PrescribedRotation::displacement_by` forms `R d - d`. With f64 kernels, or the f32
//! kernels' f64 `load_real`, that is the CPU's value bit for bit; with f32-only kernels it
//! is the same sum in f32. The WGSL has no load-shape, rotation or moisture code.
//!
//! Precision: with `SHADER_F64` on the adapter, the f32 kernels ([`ShaderReal::F32ExactCbrt`])
//! return the CPU's f32 bits (verified on lavapipe: whole runs identical); without it
//! ([`ShaderReal::F32`]) the cube root is within one ulp and the loads are formed in f32, and
//! runs differ from the CPU's at the level of f32 round-off (`verification/gpu.rs` states
//! the bound). f64 kernels need `SHADER_F64`; their cube root is within about one f64 ulp of
//! the CPU's.

mod bindings;
mod buffers;
mod pack;
mod readback;

use crate::error::{Error, Result};
use crate::gpu::context::GpuContext;
use crate::gpu::layout::*;
use crate::gpu::shaders::{Kernel, ShaderReal};
use crate::problem::Problem;
use crate::tled::element_forces::{element_forces, ElementArrays};
use crate::tled::node_update::{gather_all, CentralDifference};
use crate::tled::precompute::Discretisation;
use crate::tled::saliva_forces::SalivaState;
use crate::tled::solver::Energies;
use buffers::{bytes_of_slice, load_bytes, Buffers};
use readback::{map_and_read_after, read_buffers};
use wgpu::util::DeviceExt;

/// A stepping scalar the kernels exist for.
pub trait GpuReal: crate::tled::simd::SimdReal + bytemuck::Pod {
    const IS_F64: bool;
    /// The kernels' scalar on an adapter with (`has_f64`) or without SHADER_F64.
    fn shader_real(has_f64: bool) -> ShaderReal {
        match (Self::IS_F64, has_f64) {
            (true, _) => ShaderReal::F64,
            (false, true) => ShaderReal::F32ExactCbrt,
            (false, false) => ShaderReal::F32,
        }
    }
}
impl GpuReal for f32 {
    const IS_F64: bool = false;
}
impl GpuReal for f64 {
    const IS_F64: bool = true;
}

/// Steps recorded in one submission at most (the per-step table holds this many rows).
pub const MAX_BATCH: usize = 512;

/// A stage that [`GpuSimulation::bench_stage`] can dispatch alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    ElementForces,
    NodeUpdate,
}

/// A submitted batch whose status has not been read yet.
struct InFlight {
    /// Receives the status after the batch's last dispatch.
    staging: wgpu::Buffer,
    index: wgpu::SubmissionIndex,
}

struct Kernels {
    pipeline: wgpu::ComputePipeline,
    /// One bind group per rotation of the displacement (and saliva state) buffers.
    groups: Vec<wgpu::BindGroup>,
    workgroups: u32,
}

impl Kernels {
    /// The bind group of step `s`.
    fn group(&self, s: usize) -> &wgpu::BindGroup {
        &self.groups[s % self.groups.len()]
    }
}

pub struct GpuSimulation<T: GpuReal> {
    pub disc: Discretisation,
    ctx: GpuContext,
    el: ElementArrays<T>,
    element: Kernels,
    node: Kernels,
    bufs: Buffers,
    real: ShaderReal,
    params: Params,
    step: usize,
    num_steps: usize,
    dt: f64,
    total_time: f64,
    niftysim_timing: bool,
    u: Vec<[T; 3]>,
    u_prev: Vec<[T; 3]>,
    saliva: SalivaState<T>,
    synced: bool,
}

/// The GPU path steps every node with one step: a subcycled problem is refused (before an
/// adapter is looked for).
fn refuse_subcycles(problem: &Problem) -> Result<()> {
    match problem.numerics.subcycles {
        1 => Ok(()),
        k => Err(Error::Gpu(format!(
            "the GPU path does not subcycle the saliva layer (time.subcycles = {k}): run it \
             with --backend cpu, or without subcycles"
        ))),
    }
}

impl<T: GpuReal> GpuSimulation<T> {
    /// Validates the problem, precomputes, finds an adapter and uploads the model.
    pub fn new(problem: &Problem) -> Result<Self> {
        problem.validate()?;
        refuse_subcycles(problem)?;
        let ctx = GpuContext::new()?;
        Self::with_context(ctx, problem)
    }

    /// As [`GpuSimulation::new`] on a given device.
    pub fn with_context(ctx: GpuContext, problem: &Problem) -> Result<Self> {
        let real = T::shader_real(ctx.has_f64);
        Self::with_shader_real(ctx, problem, real)
    }

    /// As [`GpuSimulation::with_context`] with the kernels' scalar chosen (e.g. the f32-only
    /// cube root on an adapter that has f64, to test what adapters without f64 run).
    pub fn with_shader_real(ctx: GpuContext, problem: &Problem, real: ShaderReal) -> Result<Self> {
        problem.validate()?;
        if real.needs_f64() && !ctx.has_f64 {
            return Err(Error::Gpu(format!(
                "{} has no SHADER_F64: use --precision f32 with the GPU backend",
                ctx.describe()
            )));
        }
        if T::IS_F64 != (real == ShaderReal::F64) {
            return Err(Error::Gpu(format!(
                "kernels in {real:?} cannot step a {} simulation",
                T::NAME
            )));
        }
        refuse_subcycles(problem)?;
        if problem.num_steps() >= NEVER as usize {
            return Err(Error::Gpu(format!(
                "{} steps: the GPU path counts steps in 32 bits (at most {})",
                problem.num_steps(),
                NEVER - 1
            )));
        }
        let disc = Discretisation::new(problem);
        let nn = disc.num_nodes;
        let el = ElementArrays::<T>::from_discretisation(&disc);
        let cd = CentralDifference::<T>::new(problem.time.dt, problem.numerics.damping, &disc.mass);
        let packed = pack::pack(problem, &disc, &el, &cd)?;
        let (wg_e, wg_n) = buffers::check_limits(&ctx, &packed, real)?;
        let bufs = buffers::upload(&ctx, &packed, real)?;
        // bind group g serves step s with g = s % 6 (element kernel: displacement rotation
        // g % 3 and saliva parity g % 2) or g = s % 3 (node kernel)
        let kernel = |kernel, entry, groups, workgroups| -> Result<Kernels> {
            let (pipeline, groups) =
                bindings::build_kernel(&ctx, kernel, entry, real, groups, |g, name| {
                    bufs.by_name(name, g)
                })?;
            Ok(Kernels {
                pipeline,
                groups,
                workgroups,
            })
        };
        let element = kernel(Kernel::ElementForces, "element_forces", 6, wg_e)?;
        let node = kernel(Kernel::NodeUpdate, "node_update", 3, wg_n)?;
        let saliva = SalivaState::<T>::new(&disc.saliva);
        Ok(GpuSimulation {
            el,
            element,
            node,
            bufs,
            real,
            params: packed.params,
            step: 0,
            num_steps: problem.num_steps(),
            dt: problem.time.dt,
            total_time: problem.time.total_time,
            niftysim_timing: problem.numerics.niftysim_timing,
            u: vec![[T::ZERO; 3]; nn],
            u_prev: vec![[T::ZERO; 3]; nn],
            saliva,
            synced: true,
            ctx,
            disc,
        })
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }
    /// The kernels' scalar (and cube root).
    pub fn shader_real(&self) -> ShaderReal {
        self.real
    }
    /// Iterations executed so far.
    pub fn step_index(&self) -> usize {
        self.step
    }
    /// Iterations the run executes in all.
    pub fn num_steps(&self) -> usize {
        self.num_steps
    }
    /// Time of the current displacement (s).
    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }
    pub fn dt(&self) -> f64 {
        self.dt
    }
    pub fn total_time(&self) -> f64 {
        self.total_time
    }
    pub fn is_finished(&self) -> bool {
        self.step >= self.num_steps
    }
    pub fn num_elements(&self) -> usize {
        self.el.len()
    }

    /// The step row of step `s` (see the module documentation): load curves as
    /// `Simulation::assemble_external` applies them at iteration `s` (`solver::load_value`),
    /// prescribed curves and rotation matrices at `t_{s+1}` as `apply_constraints` does.
    fn fill_step_row(&self, s: usize, row: &mut [f64]) {
        pack::fill_step_row(&self.disc, s, self.dt, self.niftysim_timing, row);
    }

    /// The saliva row of step `s`: the breaking point of every saliva element at `t_s`
    /// (eqs. 6-7 in f64, as `saliva_forces` evaluates them); `evaporated` is scratch, one
    /// per saliva group.
    fn fill_saliva_row(&self, s: usize, row: &mut [T], evaporated: &mut [f64]) {
        let sp = &self.disc.saliva;
        let t = s as f64 * self.dt;
        sp.evaporated_into(t, evaporated);
        for (k, z) in row.iter_mut().enumerate().take(sp.elements.len()) {
            let (_, zk) = sp.moisture_and_breaking_point(k, evaporated[sp.group[k] as usize], t);
            *z = T::from_f64(zk);
        }
    }

    /// Advances one iteration (one submission: prefer [`GpuSimulation::step_many`]).
    pub fn step(&mut self) -> Result<()> {
        self.step_many(1)
    }

    /// Advances `n` iterations (fewer if the run ends first), [`MAX_BATCH`] per submission.
    /// On divergence the state is the one before the failing step and the error names it.
    ///
    /// Batches are pipelined: batch `k + 1` is prepared, recorded and submitted before the
    /// status of batch `k` is waited for, so the CPU's share of a step (`host/*` in
    /// `benches/gpu.rs`) overlaps the GPU's. This is safe because every kernel does nothing
    /// once a failure is recorded (so a batch submitted after a failing one leaves the state
    /// alone) and because a queued buffer write never affects work submitted before it.
    pub fn step_many(&mut self, n: usize) -> Result<()> {
        let mut left = n.min(self.num_steps.saturating_sub(self.step));
        let mut pending: Option<InFlight> = None;
        while left > 0 {
            let b = left.min(MAX_BATCH);
            let next = self.submit_batch(b);
            left -= b;
            if let Some(prev) = pending.replace(next) {
                self.finish_batch(prev)?;
            }
        }
        match pending {
            Some(last) => self.finish_batch(last),
            None => Ok(()),
        }
    }

    /// The per-step data of steps `self.step .. self.step + n` (host side, f64 math).
    fn fill_rows(&self, n: usize, table: &mut Vec<T>, rows: &mut Vec<f64>, info: &mut Vec<u8>) {
        let stride = self.params.table_stride as usize;
        let rs = self.params.row_stride as usize;
        table.clear();
        table.resize(n * stride, T::ZERO);
        rows.clear();
        rows.resize(n * rs, 0.0);
        info.clear();
        info.resize(n * self.bufs.step_stride as usize, 0);
        let mut evaporated = vec![0.0; self.disc.saliva.groups.len()];
        for j in 0..n {
            let s = self.step + j;
            self.fill_saliva_row(s, &mut table[j * stride..(j + 1) * stride], &mut evaporated);
            self.fill_step_row(s, &mut rows[j * rs..(j + 1) * rs]);
            let si = StepInfo {
                step: s as u32,
                row: j as u32,
                _pad0: 0,
                _pad1: 0,
            };
            let o = j * self.bufs.step_stride as usize;
            info[o..o + std::mem::size_of::<StepInfo>()].copy_from_slice(bytemuck::bytes_of(&si));
        }
    }

    /// Records the dispatches of `n` steps from `self.step` into one compute pass.
    fn encode_steps(&self, n: usize) -> wgpu::CommandEncoder {
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("tled steps"),
                timestamp_writes: None,
            });
            for j in 0..n {
                let s = self.step + j;
                let off = [(j as u64 * self.bufs.step_stride) as u32];
                for k in [&self.element, &self.node] {
                    pass.set_pipeline(&k.pipeline);
                    pass.set_bind_group(0, k.group(s), &off);
                    pass.dispatch_workgroups(k.workgroups, 1, 1);
                }
            }
        }
        enc
    }

    /// For benchmarks: what a batch of `n` steps costs the CPU on any adapter (the per-step
    /// data and the recording of every dispatch), without uploading or submitting anything;
    /// the state does not advance. `n` is capped at [`MAX_BATCH`].
    pub fn bench_host(&self, n: usize) -> wgpu::CommandBuffer {
        let n = n.min(MAX_BATCH);
        let (mut table, mut rows, mut info) = (Vec::new(), Vec::new(), Vec::new());
        self.fill_rows(n, &mut table, &mut rows, &mut info);
        std::hint::black_box((&table, &rows, &info));
        self.encode_steps(n).finish()
    }

    /// Uploads the per-step data of `n` steps from `self.step`, submits them with a copy of
    /// the status behind them and advances `self.step` (provisionally: a failure found by
    /// [`Self::finish_batch`] sets it back).
    fn submit_batch(&mut self, n: usize) -> InFlight {
        let (mut table, mut rows, mut info) = (Vec::new(), Vec::new(), Vec::new());
        self.fill_rows(n, &mut table, &mut rows, &mut info);
        let q = &self.ctx.queue;
        q.write_buffer(&self.bufs.table, 0, bytemuck::cast_slice(&table));
        q.write_buffer(&self.bufs.step_row, 0, &load_bytes(&rows, self.real));
        q.write_buffer(&self.bufs.step_info, 0, &info);
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("status read back"),
            size: std::mem::size_of::<Status>() as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.encode_steps(n);
        enc.copy_buffer_to_buffer(
            &self.bufs.status,
            0,
            &staging,
            0,
            std::mem::size_of::<Status>() as u64,
        );
        let index = q.submit([enc.finish()]);
        self.step += n;
        self.synced = false;
        InFlight { staging, index }
    }

    /// Waits for a submitted batch and reads the status behind it: the first failure of the
    /// run so far, if any, becomes the error and the current step.
    fn finish_batch(&mut self, b: InFlight) -> Result<()> {
        let bytes = map_and_read_after(
            &self.ctx,
            &b.staging,
            Some(b.index),
            [std::mem::size_of::<Status>() as u64].into_iter(),
        )?;
        let st: Status = bytemuck::pod_read_unaligned(&bytes[0]);
        if st != Status::OK {
            let (step, element, node, reason) = if st.element_step <= st.node_step {
                (
                    st.element_step as usize,
                    Some(st.element as usize),
                    None,
                    "element inverted or degenerate (det F <= 0 or not finite)",
                )
            } else {
                (
                    st.node_step as usize,
                    None,
                    Some(st.node as usize),
                    "non-finite displacement",
                )
            };
            self.step = step;
            return Err(Error::Diverged {
                step,
                time: step as f64 * self.dt,
                element,
                node,
                reason: reason.into(),
            });
        }
        Ok(())
    }

    /// For benchmarks: dispatches one stage `reps` times at the current step, in one pass
    /// and one submission, and waits for it. `element_forces` rewrites the same blocks and
    /// `node_update` the same `u_{s+1}` each time, so the state does not advance (the
    /// saliva rule, which carries state, is not offered).
    pub fn bench_stage(&mut self, stage: Stage, reps: usize) -> Result<()> {
        let (mut table, mut rows, mut info) = (Vec::new(), Vec::new(), Vec::new());
        self.fill_rows(1, &mut table, &mut rows, &mut info);
        let si = StepInfo {
            step: self.step as u32,
            row: 0,
            _pad0: 0,
            _pad1: 0,
        };
        let q = &self.ctx.queue;
        q.write_buffer(&self.bufs.table, 0, bytemuck::cast_slice(&table));
        q.write_buffer(&self.bufs.step_row, 0, &load_bytes(&rows, self.real));
        q.write_buffer(&self.bufs.step_info, 0, bytemuck::bytes_of(&si));
        let k = match stage {
            Stage::ElementForces => &self.element,
            Stage::NodeUpdate => &self.node,
        };
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&k.pipeline);
            pass.set_bind_group(0, k.group(self.step), &[0]);
            for _ in 0..reps {
                pass.dispatch_workgroups(k.workgroups, 1, 1);
            }
        }
        let idx = q.submit([enc.finish()]);
        self.ctx
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(idx),
                timeout: None,
            })
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        self.ctx.check_uncaptured()?;
        self.synced = false;
        Ok(())
    }

    /// Reads the displacement and the saliva state back (once per state; cheap to repeat).
    pub fn sync(&mut self) -> Result<()> {
        if self.synced {
            return Ok(());
        }
        let s = self.step;
        let mut out = read_buffers(
            &self.ctx,
            &[
                &self.bufs.u[s % 3],
                &self.bufs.u[(s + 2) % 3],
                &self.bufs.sal_real[s % 2],
                &self.bufs.sal_state[s % 2],
            ],
        )?;
        let nn = self.disc.num_nodes;
        let to_vec3 = |b: &[u8]| -> Vec<[T; 3]> {
            let v: Vec<T> = bytemuck::pod_collect_to_vec(&b[..3 * nn * std::mem::size_of::<T>()]);
            v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        };
        self.u = to_vec3(&out[0]);
        self.u_prev = to_vec3(&out[1]);
        let sp = &self.disc.saliva;
        let ns = sp.elements.len();
        if ns > 0 {
            let real: Vec<T> =
                bytemuck::pod_collect_to_vec(&out[2][..25 * ns * std::mem::size_of::<T>()]);
            let state: Vec<u32> = bytemuck::pod_collect_to_vec(&out[3][..8 * ns]);
            let st = &mut self.saliva;
            for k in 0..ns {
                st.previous[k] =
                    std::array::from_fn(|a| std::array::from_fn(|i| real[25 * k + 3 * a + i]));
                st.broken[k] = state[2 * k] != 0;
                st.broken_at[k] = if state[2 * k + 1] == NEVER {
                    f64::NAN
                } else {
                    state[2 * k + 1] as f64 * self.dt
                };
                st.q[k] = real[25 * k + 24].to_f64();
            }
            if s > 0 {
                // moisture and Z of the last step executed, as saliva_forces records them
                let t = (s - 1) as f64 * self.dt;
                sp.evaporated_into(t, &mut st.evaporated);
                for k in 0..ns {
                    let g = sp.group[k] as usize;
                    (st.moisture[k], st.z[k]) =
                        sp.moisture_and_breaking_point(k, st.evaporated[g], t);
                }
            }
        }
        out.clear();
        self.synced = true;
        Ok(())
    }

    /// The current displacement (read back if needed).
    pub fn displacement(&mut self) -> Result<&[[T; 3]]> {
        self.sync()?;
        Ok(&self.u)
    }
    pub fn previous_displacement(&mut self) -> Result<&[[T; 3]]> {
        self.sync()?;
        Ok(&self.u_prev)
    }
    pub fn displacement_f64(&mut self) -> Result<Vec<[f64; 3]>> {
        self.sync()?;
        Ok(self.u.iter().map(|v| v.map(T::to_f64)).collect())
    }
    /// The saliva elements' state after the last step (read back if needed).
    pub fn saliva(&mut self) -> Result<&SalivaState<T>> {
        self.sync()?;
        Ok(&self.saliva)
    }

    /// Sets the current and previous displacement (an initial condition), as
    /// `Simulation::set_state`.
    pub fn set_state(&mut self, u: &[[f64; 3]], u_prev: &[[f64; 3]]) {
        let s = self.step;
        let flat =
            |v: &[[f64; 3]]| -> Vec<T> { v.iter().flatten().map(|&x| T::from_f64(x)).collect() };
        self.ctx
            .queue
            .write_buffer(&self.bufs.u[s % 3], 0, bytemuck::cast_slice(&flat(u)));
        self.ctx.queue.write_buffer(
            &self.bufs.u[(s + 2) % 3],
            0,
            bytemuck::cast_slice(&flat(u_prev)),
        );
        self.synced = false;
    }

    /// Energies of the read-back state, as `Simulation::energies` computes them (f64).
    pub fn energies(&mut self) -> Result<Energies> {
        self.sync()?;
        let u: Vec<[f64; 3]> = self.u.iter().map(|v| v.map(T::to_f64)).collect();
        let mut kinetic = 0.0;
        for n in 0..self.disc.num_nodes {
            let mut v2 = 0.0;
            for k in 0..3 {
                let v = (self.u[n][k].to_f64() - self.u_prev[n][k].to_f64()) / self.dt;
                v2 += v * v;
            }
            kinetic += 0.5 * self.disc.mass[n] * v2;
        }
        Ok(Energies {
            kinetic,
            strain: crate::tled::solver::strain_energy(&self.disc, &u),
        })
    }

    /// Internal nodal forces at the read-back state (N), evaluated by the CPU stages in the
    /// same precision (saliva elements broken at the last step contribute their last force).
    pub fn internal_forces(&mut self) -> Result<Vec<[f64; 3]>> {
        self.sync()?;
        let mut elem_f = vec![[[T::ZERO; 3]; 8]; self.el.len()];
        element_forces(&self.el, &self.u, &mut elem_f);
        for (k, &e) in self.disc.saliva.elements.iter().enumerate() {
            if self.saliva.broken[k] {
                elem_f[e as usize] = self.saliva.previous[k];
            }
        }
        Ok(gather_all(&self.disc.gather, &elem_f, self.disc.num_nodes)
            .into_iter()
            .map(|f| f.map(T::to_f64))
            .collect())
    }
}

/// Runs one entry point of `shaders/function_tests.wgsl` on `records` input records and
/// returns `records * out_len` outputs: the harness `verification/gpu.rs` uses to compare
/// each shared WGSL function with its Rust twin.
pub fn run_function_test<T: GpuReal>(
    ctx: &GpuContext,
    real: ShaderReal,
    entry: &str,
    input: &[T],
    records: usize,
    out_len: usize,
) -> Result<Vec<T>> {
    if real.needs_f64() && !ctx.has_f64 {
        return Err(Error::Gpu(format!("{} has no SHADER_F64", ctx.describe())));
    }
    let d = &ctx.device;
    let (inp, out, count) = ctx.scoped("function test buffers", || {
        let inp = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("input"),
            contents: &bytes_of_slice(input),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let out = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("output"),
            contents: &bytes_of_slice(&vec![T::ZERO; records * out_len]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let count = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("count"),
            contents: bytemuck::cast_slice(&[records as u32, 0, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        (inp, out, count)
    })?;
    let (pipeline, groups) = bindings::build_kernel(
        ctx,
        Kernel::FunctionTests,
        entry,
        real,
        1,
        |_, name| match name {
            "input" => Some(&inp),
            "output" => Some(&out),
            "count" => Some(&count),
            _ => None,
        },
    )?;
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &groups[0], &[]);
        pass.dispatch_workgroups((records as u32).div_ceil(WORKGROUP_SIZE).max(1), 1, 1);
    }
    ctx.queue.submit([enc.finish()]);
    let bytes = read_buffers(ctx, &[&out])?;
    Ok(bytemuck::pod_collect_to_vec(
        &bytes[0][..records * out_len * std::mem::size_of::<T>()],
    ))
}
