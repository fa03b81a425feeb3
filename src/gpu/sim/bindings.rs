//! Pipelines and bind groups from the kernels' own declarations: the WGSL source of a
//! kernel is parsed with naga, and each `@group(0) @binding(i) var<...> name` gives the
//! binding's index, its kind (uniform, read-only or read-write storage; the uniform of type
//! `StepInfo` takes a dynamic offset, one per step of a batch) and the name by which the
//! Rust side supplies its buffer. Nothing lists the bindings a second time: a buffer is
//! looked up by the name the kernel declares, and a declared name without a buffer is an
//! error naming the kernel and the binding.

use crate::error::{Error, Result};
use crate::gpu::context::GpuContext;
use crate::gpu::layout::StepInfo;
use crate::gpu::shaders::{kernel_source, Kernel, ShaderReal};
use std::num::NonZeroU64;

/// The kind of a buffer binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bind {
    Uniform,
    /// A uniform bound at one `StepInfo` with a dynamic offset.
    UniformDyn,
    Read,
    ReadWrite,
}

/// One binding of a kernel as its WGSL declares it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Declared {
    pub binding: u32,
    pub name: String,
    pub kind: Bind,
}

/// The group-0 bindings that `src` declares, by binding index.
pub(crate) fn declared_bindings(src: &str) -> std::result::Result<Vec<Declared>, String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    let mut out = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var.name.clone().unwrap_or_default();
        if rb.group != 0 {
            return Err(format!("binding `{name}` is in group {}, not 0", rb.group));
        }
        let kind = match var.space {
            naga::AddressSpace::Uniform => {
                if module.types[var.ty].name.as_deref() == Some("StepInfo") {
                    Bind::UniformDyn
                } else {
                    Bind::Uniform
                }
            }
            naga::AddressSpace::Storage { access } => {
                if access.contains(naga::StorageAccess::STORE) {
                    Bind::ReadWrite
                } else {
                    Bind::Read
                }
            }
            other => return Err(format!("binding `{name}` is in address space {other:?}")),
        };
        out.push(Declared {
            binding: rb.binding,
            name,
            kind,
        });
    }
    out.sort_by_key(|d| d.binding);
    Ok(out)
}

fn layout_entry(d: &Declared) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: d.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: match d.kind {
                Bind::Uniform | Bind::UniformDyn => wgpu::BufferBindingType::Uniform,
                Bind::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Bind::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            },
            has_dynamic_offset: d.kind == Bind::UniformDyn,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A compute pipeline for `entry` of `kernel`, and `groups` bind groups: bind group `g`
/// binds, at each declared binding, `buffer(g, name)`.
pub(crate) fn build_kernel<'b>(
    ctx: &GpuContext,
    kernel: Kernel,
    entry: &str,
    real: ShaderReal,
    groups: usize,
    buffer: impl Fn(usize, &str) -> Option<&'b wgpu::Buffer>,
) -> Result<(wgpu::ComputePipeline, Vec<wgpu::BindGroup>)> {
    let src = kernel_source(kernel, real);
    let declared = declared_bindings(&src)
        .map_err(|e| Error::Gpu(format!("kernel `{}`: {e}", kernel.name())))?;
    // every declared binding has its buffer, in every group
    let mut sets: Vec<Vec<&wgpu::Buffer>> = Vec::with_capacity(groups);
    for g in 0..groups {
        let mut set = Vec::with_capacity(declared.len());
        for d in &declared {
            set.push(buffer(g, &d.name).ok_or_else(|| {
                Error::Gpu(format!(
                    "kernel `{}` declares binding {} `{}`, for which the simulation has no buffer",
                    kernel.name(),
                    d.binding,
                    d.name
                ))
            })?);
        }
        sets.push(set);
    }
    let d = &ctx.device;
    ctx.scoped(&format!("building kernel `{entry}`"), || {
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(kernel.name()),
            source: wgpu::ShaderSource::Wgsl(src.as_str().into()),
        });
        let entries: Vec<_> = declared.iter().map(layout_entry).collect();
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(entry),
            entries: &entries,
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let groups = sets
            .iter()
            .map(|bufs| {
                let entries: Vec<wgpu::BindGroupEntry> = bufs
                    .iter()
                    .zip(&declared)
                    .map(|(b, dcl)| wgpu::BindGroupEntry {
                        binding: dcl.binding,
                        resource: match dcl.kind {
                            Bind::UniformDyn => {
                                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                    buffer: b,
                                    offset: 0,
                                    size: NonZeroU64::new(std::mem::size_of::<StepInfo>() as u64),
                                })
                            }
                            _ => b.as_entire_binding(),
                        },
                    })
                    .collect();
                d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(entry),
                    layout: &bgl,
                    entries: &entries,
                })
            })
            .collect();
        (pipeline, groups)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::sim::buffers::Slot;

    fn declared(kernel: Kernel) -> Vec<Declared> {
        declared_bindings(&kernel_source(kernel, ShaderReal::F32)).unwrap()
    }

    /// The kinds naga reads from the declarations (the lists that used to be kept by hand).
    #[test]
    fn kinds_come_from_the_declarations() {
        use Bind::*;
        let kinds = |k| declared(k).iter().map(|d| d.kind).collect::<Vec<_>>();
        assert_eq!(
            kinds(Kernel::ElementForces),
            [
                Uniform, UniformDyn, Read, Read, Read, Read, Read, ReadWrite, ReadWrite, Read,
                Read, Read, Read, ReadWrite, Read, ReadWrite,
            ]
        );
        assert_eq!(
            kinds(Kernel::NodeUpdate),
            [
                Uniform, UniformDyn, Read, Read, ReadWrite, Read, Read, Read, Read, Read, Read,
                Read, Read, Read, ReadWrite,
            ]
        );
        assert_eq!(kinds(Kernel::FunctionTests), [Read, ReadWrite, Uniform]);
    }

    /// Every binding the two stepping kernels declare, in every precision, is one the
    /// simulation's buffers supply; indices are 0, 1, 2, ... without gaps.
    #[test]
    fn every_declared_binding_has_a_buffer() {
        for real in [ShaderReal::F32, ShaderReal::F32ExactCbrt, ShaderReal::F64] {
            for k in [Kernel::ElementForces, Kernel::NodeUpdate] {
                let d = declared_bindings(&kernel_source(k, real)).unwrap();
                for (i, b) in d.iter().enumerate() {
                    assert_eq!(b.binding as usize, i, "{k:?}: bindings have a gap");
                    assert!(
                        Slot::of_name(&b.name).is_some(),
                        "{k:?} {real:?}: no buffer for binding `{}`",
                        b.name
                    );
                }
            }
        }
    }

    #[test]
    fn a_binding_outside_group_0_is_refused() {
        let e = declared_bindings("@group(1) @binding(0) var<storage, read> x: array<f32>;")
            .unwrap_err();
        assert!(e.contains("group 1"), "{e}");
    }
}
