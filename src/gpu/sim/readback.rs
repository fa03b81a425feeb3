//! Reading GPU buffers back to the host: one staging buffer per read, mapped once the
//! submissions before it are done.

use crate::error::{Error, Result};
use crate::gpu::context::GpuContext;

/// Reads buffers back (each whole) in one submission.
pub(crate) fn read_buffers(ctx: &GpuContext, bufs: &[&wgpu::Buffer]) -> Result<Vec<Vec<u8>>> {
    let d = &ctx.device;
    let total: u64 = bufs.iter().map(|b| b.size()).sum();
    let staging = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: total.max(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = d.create_command_encoder(&Default::default());
    let mut off = 0;
    for b in bufs {
        enc.copy_buffer_to_buffer(b, 0, &staging, off, b.size());
        off += b.size();
    }
    ctx.queue.submit([enc.finish()]);
    map_and_read(ctx, &staging, bufs.iter().map(|b| b.size()))
}

pub(crate) fn map_and_read(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    sizes: impl Iterator<Item = u64>,
) -> Result<Vec<Vec<u8>>> {
    map_and_read_after(ctx, staging, None, sizes)
}

/// As [`map_and_read`], waiting only for submission `index` (and those before it) when given.
pub(crate) fn map_and_read_after(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    index: Option<wgpu::SubmissionIndex>,
    sizes: impl Iterator<Item = u64>,
) -> Result<Vec<Vec<u8>>> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    let wait = match index {
        Some(i) => wgpu::PollType::Wait {
            submission_index: Some(i),
            timeout: None,
        },
        None => wgpu::PollType::wait_indefinitely(),
    };
    ctx.device
        .poll(wait)
        .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
    ctx.check_uncaptured()?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("read back: {e}")))?
        .map_err(|e| Error::Gpu(format!("read back: {e}")))?;
    let out = {
        let view = staging
            .get_mapped_range(..)
            .map_err(|e| Error::Gpu(format!("read back: {e}")))?;
        let mut out = Vec::new();
        let mut off = 0usize;
        for s in sizes {
            out.push(view[off..off + s as usize].to_vec());
            off += s as usize;
        }
        out
    };
    staging.unmap();
    Ok(out)
}
