use std::sync::{Arc, Mutex};

use crate::render::RenderError;

/// An adapter and device on Vulkan, with wgpu's uncaught errors collected
/// instead of panicking (its default), so that a bad upload becomes a
/// `RenderError` and the renderer stays usable.
pub(super) struct Context {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    errors: Arc<Mutex<Vec<String>>>,
}

impl Context {
    pub fn new() -> Result<Self, RenderError> {
        // Vulkan only: GL's 1D textures and array layers are unreliable,
        // and CI runs lavapipe, which is Vulkan.
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            flags: wgpu::InstanceFlags::empty().with_env(),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("caveray"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(format!("{} refused a device: {e}", info.name)))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Self {
            device,
            queue,
            info,
            limits,
            errors,
        })
    }

    /// Fails with the first error wgpu reported since the last check.
    pub fn check(&self) -> Result<(), RenderError> {
        let mut errors = self
            .errors
            .lock()
            .map_err(|_| RenderError::Gpu("the GPU error log was poisoned by a panic".into()))?;
        if errors.is_empty() {
            return Ok(());
        }
        let first = errors.remove(0);
        errors.clear();
        Err(RenderError::Gpu(first))
    }

    /// Blocks until the GPU has finished everything submitted.
    pub fn wait(&self) -> Result<(), RenderError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| RenderError::Gpu(e.to_string()))
    }

    /// Runs one compute dispatch on its own and waits for it; returns the
    /// milliseconds from submission to completion.
    pub fn dispatch(
        &self,
        pipeline: &wgpu::ComputePipeline,
        groups: &[&wgpu::BindGroup],
        workgroups: [u32; 3],
    ) -> Result<f64, RenderError> {
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            for (i, group) in groups.iter().enumerate() {
                pass.set_bind_group(i as u32, *group, &[]);
            }
            pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        }
        let commands = encoder.finish();
        let start = std::time::Instant::now();
        self.queue.submit([commands]);
        self.wait()?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        self.check()?;
        Ok(ms)
    }

    /// Copies a MAP_READ buffer's first `bytes` back to the host.
    pub fn read(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, RenderError> {
        let slice = buffer.slice(..bytes);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|_| RenderError::Gpu("read-back was cancelled".into()))?
            .map_err(|e| RenderError::Gpu(format!("read-back failed: {e}")))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Gpu(format!("read-back failed: {e}")))?
            .to_vec();
        buffer.unmap();
        Ok(data)
    }
}
