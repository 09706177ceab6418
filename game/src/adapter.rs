//! The GPU every command renders on, announced on stderr: each image and figure says which adapter made it.

use anyhow::Result;
use raykin::gpu::GpuContext;

pub fn open_gpu() -> Result<GpuContext> {
    let ctx = GpuContext::new_headless()?;
    eprintln!("raykin: adapter: {}", ctx.describe());
    Ok(ctx)
}
