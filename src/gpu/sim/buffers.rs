//! The simulation's GPU buffers, by name: the adapter's limits checked against the packed
//! model before anything is allocated, the upload, and the buffer that each kernel
//! binding (by the name its WGSL declares, see `bindings`) reads in each bind group.

use crate::error::{Error, Result};
use crate::gpu::context::GpuContext;
use crate::gpu::layout::*;
use crate::gpu::shaders::ShaderReal;
use crate::gpu::sim::pack::Packed;
use crate::gpu::sim::{GpuReal, MAX_BATCH};
use wgpu::util::DeviceExt;

/// The role of a buffer, from the name a kernel gives its binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Slot {
    Params,
    StepInfo,
    /// Displacement, `k` places on in the rotation of the three buffers: 0 is `u_s`, 1 is
    /// `u_{s+1}` (written), 2 is `u_{s-1}`.
    U(usize),
    Conn,
    Dhdx,
    Gamma,
    Escal,
    ElemF,
    Status,
    Table,
    SalMeta,
    SalConst,
    /// Saliva state read this step (`false`) or written (`true`).
    SalReal(bool),
    SalState(bool),
    Gather,
    NodeA,
    LoadKey,
    LoadVal,
    StepRow,
    DofSlots,
    ImpKey,
    ImpCoef,
}

impl Slot {
    /// The buffer a binding of this name reads (names as in `shaders/*.wgsl`).
    pub(crate) fn of_name(name: &str) -> Option<Slot> {
        use Slot::*;
        Some(match name {
            "params" => Params,
            "step" => StepInfo,
            "u" => U(0),
            "u_next" => U(1),
            "u_prev" => U(2),
            "conn" => Conn,
            "dhdx" => Dhdx,
            "gamma" => Gamma,
            "escal" => Escal,
            "elem_f" => ElemF,
            "status" => Status,
            "table" => Table,
            "sal_meta" => SalMeta,
            "sal_const" => SalConst,
            "sal_real_in" => SalReal(false),
            "sal_real_out" => SalReal(true),
            "sal_state_in" => SalState(false),
            "sal_state_out" => SalState(true),
            "gather" => Gather,
            "node_a" => NodeA,
            "load_key" => LoadKey,
            "load_val" => LoadVal,
            "step_row" => StepRow,
            "dof_slot" => DofSlots,
            "imp_key" => ImpKey,
            "imp_coef" => ImpCoef,
            _ => return None,
        })
    }
}

/// Every buffer of a simulation.
pub(crate) struct Buffers {
    pub params: wgpu::Buffer,
    /// One `StepInfo` per step of a batch, `step_stride` bytes apart.
    pub step_info: wgpu::Buffer,
    pub step_stride: u64,
    /// The displacement in rotation: `u[s % 3]` is `u_s`.
    pub u: [wgpu::Buffer; 3],
    pub conn: wgpu::Buffer,
    pub dhdx: wgpu::Buffer,
    pub gamma: wgpu::Buffer,
    pub escal: wgpu::Buffer,
    pub elem_f: wgpu::Buffer,
    pub status: wgpu::Buffer,
    /// Per-step saliva rows (breaking points), in the stepping scalar.
    pub table: wgpu::Buffer,
    pub sal_meta: wgpu::Buffer,
    pub sal_const: wgpu::Buffer,
    /// Saliva state, double-buffered by step parity: per saliva element the previous
    /// modified force (24) and Q (1); broken and first broken step (2 u32).
    pub sal_real: [wgpu::Buffer; 2],
    pub sal_state: [wgpu::Buffer; 2],
    pub gather: wgpu::Buffer,
    pub node_a: wgpu::Buffer,
    pub load_key: wgpu::Buffer,
    pub load_val: wgpu::Buffer,
    /// Per-step rows in `load_real` (see the module documentation of `gpu::sim`).
    pub step_row: wgpu::Buffer,
    pub dof_slot: wgpu::Buffer,
    pub imp_key: wgpu::Buffer,
    pub imp_coef: wgpu::Buffer,
}

impl Buffers {
    /// The buffer of `slot` in bind group `g`: displacement rotation `g % 3`, saliva parity
    /// `g % 2` (bind group `s % 6` serves step `s`).
    pub(crate) fn get(&self, slot: Slot, g: usize) -> &wgpu::Buffer {
        let (r, p) = (g % 3, g % 2);
        match slot {
            Slot::Params => &self.params,
            Slot::StepInfo => &self.step_info,
            Slot::U(k) => &self.u[(r + k) % 3],
            Slot::Conn => &self.conn,
            Slot::Dhdx => &self.dhdx,
            Slot::Gamma => &self.gamma,
            Slot::Escal => &self.escal,
            Slot::ElemF => &self.elem_f,
            Slot::Status => &self.status,
            Slot::Table => &self.table,
            Slot::SalMeta => &self.sal_meta,
            Slot::SalConst => &self.sal_const,
            Slot::SalReal(out) => &self.sal_real[(p + out as usize) % 2],
            Slot::SalState(out) => &self.sal_state[(p + out as usize) % 2],
            Slot::Gather => &self.gather,
            Slot::NodeA => &self.node_a,
            Slot::LoadKey => &self.load_key,
            Slot::LoadVal => &self.load_val,
            Slot::StepRow => &self.step_row,
            Slot::DofSlots => &self.dof_slot,
            Slot::ImpKey => &self.imp_key,
            Slot::ImpCoef => &self.imp_coef,
        }
    }

    /// The buffer a binding called `name` reads in bind group `g`.
    pub(crate) fn by_name(&self, name: &str, g: usize) -> Option<&wgpu::Buffer> {
        Slot::of_name(name).map(|s| self.get(s, g))
    }
}

/// Refuses a model the adapter cannot bind (rather than fail inside wgpu), and returns the
/// workgroup counts of the element and node kernels.
pub(crate) fn check_limits<T: GpuReal>(
    ctx: &GpuContext,
    p: &Packed<T>,
    real: ShaderReal,
) -> Result<(u32, u32)> {
    let max_bind = ctx.limits.max_storage_buffer_binding_size;
    let row_stride = p.params.row_stride as usize;
    let biggest = [
        (
            p.gamma.len() * std::mem::size_of::<T>(),
            "hourglass vectors",
        ),
        (
            p.dhdx.len() * std::mem::size_of::<T>(),
            "element force blocks",
        ),
        (MAX_BATCH * row_stride * real.load_size(), "per-step rows"),
        (p.imp_key.len() * 4, "imposed-value terms"),
        (p.gather.len() * 4, "gather lists"),
    ];
    for (bytes, what) in biggest {
        if bytes as u64 > max_bind.min(ctx.limits.max_buffer_size) {
            return Err(Error::Gpu(format!(
                "the model is too large for {}: its {what} take {bytes} bytes, the adapter binds at most {max_bind}",
                ctx.describe()
            )));
        }
    }
    let wg = |n: usize| -> Result<u32> {
        let g = (n as u64).div_ceil(WORKGROUP_SIZE as u64).max(1);
        if g > ctx.limits.max_compute_workgroups_per_dimension as u64 {
            return Err(Error::Gpu(format!(
                "{n} work items exceed the adapter's {} workgroups of {WORKGROUP_SIZE}",
                ctx.limits.max_compute_workgroups_per_dimension
            )));
        }
        Ok(g as u32)
    };
    Ok((
        wg(p.params.num_elements as usize)?,
        wg(p.params.num_nodes as usize)?,
    ))
}

/// Creates and fills every buffer of the packed model.
pub(crate) fn upload<T: GpuReal>(
    ctx: &GpuContext,
    p: &Packed<T>,
    real: ShaderReal,
) -> Result<Buffers> {
    let d = &ctx.device;
    let nn = p.params.num_nodes as usize;
    let ne = p.params.num_elements as usize;
    let step_stride = (ctx.limits.min_uniform_buffer_offset_alignment as u64)
        .max(std::mem::size_of::<StepInfo>() as u64);
    ctx.scoped("uploading the model", || {
        let storage = |label: &str, bytes: Vec<u8>, extra: wgpu::BufferUsages| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::STORAGE | extra,
            })
        };
        let none = wgpu::BufferUsages::empty();
        let rw = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let zeros = vec![T::ZERO; 3 * nn];
        Buffers {
            params: d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::bytes_of(&p.params),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            step_info: d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("step info"),
                size: step_stride * MAX_BATCH as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            step_stride,
            u: [
                storage("u0", bytes_of_slice(&zeros), rw),
                storage("u1", bytes_of_slice(&zeros), rw),
                storage("u2", bytes_of_slice(&zeros), rw),
            ],
            table: storage(
                "per-step saliva rows",
                bytes_of_slice(&vec![T::ZERO; MAX_BATCH * p.params.table_stride as usize]),
                wgpu::BufferUsages::COPY_DST,
            ),
            conn: storage("conn", bytes_of_slice(&p.conn), none),
            dhdx: storage("dhdx", bytes_of_slice(&p.dhdx), none),
            gamma: storage("gamma", bytes_of_slice(&p.gamma), none),
            escal: storage("escal", bytes_of_slice(&p.escal), none),
            elem_f: storage("elem_f", bytes_of_slice(&vec![T::ZERO; 24 * ne]), none),
            status: storage("status", bytes_of_slice(&[Status::OK]), rw),
            gather: storage("gather", bytes_of_slice(&p.gather), none),
            node_a: storage("node_a", bytes_of_slice(&p.node_a), none),
            load_key: storage("load_key", bytes_of_slice(&p.load_key), none),
            load_val: storage("load_val", load_bytes(&p.load_val, real), none),
            step_row: storage(
                "per-step rows",
                load_bytes(&vec![0.0; MAX_BATCH * p.params.row_stride as usize], real),
                wgpu::BufferUsages::COPY_DST,
            ),
            dof_slot: storage("dof_slot", bytes_of_slice(&p.dof_slot), none),
            imp_key: storage("imp_key", bytes_of_slice(&p.imp_key), none),
            imp_coef: storage("imp_coef", load_bytes(&p.imp_coef, real), none),
            sal_meta: storage("sal_meta", bytes_of_slice(&p.sal_meta), none),
            sal_const: storage("sal_const", bytes_of_slice(&p.sal_const), none),
            sal_real: [
                storage("sal_real0", bytes_of_slice(&p.sal_real0), rw),
                storage("sal_real1", bytes_of_slice(&p.sal_real0), rw),
            ],
            sal_state: [
                storage("sal_state0", bytes_of_slice(&p.sal_state0), rw),
                storage("sal_state1", bytes_of_slice(&p.sal_state0), rw),
            ],
        }
    })
}

/// Load magnitudes or curve values in the kernels' `load_real` (f64 wherever the kernels
/// may use f64, so that each load entry is the f64 product rounded once, as on the CPU).
pub(crate) fn load_bytes(v: &[f64], real: ShaderReal) -> Vec<u8> {
    if real.needs_f64() {
        bytes_of_slice(v)
    } else {
        bytes_of_slice(&v.iter().map(|&x| x as f32).collect::<Vec<f32>>())
    }
}

/// The bytes of `v`, padded to a multiple of 16 (and at least 16: no zero-sized bindings).
pub(crate) fn bytes_of_slice<T: bytemuck::Pod>(v: &[T]) -> Vec<u8> {
    let mut b = bytemuck::cast_slice::<T, u8>(v).to_vec();
    b.resize(b.len().max(16).div_ceil(16) * 16, 0);
    b
}
