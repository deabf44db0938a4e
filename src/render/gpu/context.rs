//! What every pass shares: the adapter and device, what the adapter
//! allows, the pass clock, and how a pass is dispatched.

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

use serde::Serialize;

use crate::render::frame::FrameDesc;
use crate::render::{RenderError, Watch};

/// Invocations per workgroup along x and y.
pub(super) const WORKGROUP: u32 = 8;

/// Bytes between bands' entries in a band buffer: the largest uniform
/// offset alignment WebGPU allows an adapter to ask for.
pub(super) const BAND_STRIDE: u32 = 256;

/// A compute pass: its pipeline, its bind groups from 0 on, and, for a
/// banded pass, the group after them, bound at each band's dynamic offset.
pub(super) struct Pass<'a> {
    pub pipeline: &'a wgpu::ComputePipeline,
    pub groups: &'a [&'a wgpu::BindGroup],
    pub band: Option<&'a wgpu::BindGroup>,
}

/// Where the GPU pass times come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PassClock {
    /// Timestamps the GPU writes at the start and end of each pass.
    GpuTimestamps,
    /// The host's clock from submission to completion (adapters without
    /// timestamp queries, and software ones); includes the submission's
    /// overhead.
    CpuClock,
}

impl PassClock {
    pub fn name(self) -> &'static str {
        match self {
            PassClock::GpuTimestamps => "gpu-timestamps",
            PassClock::CpuClock => "cpu-clock",
        }
    }
}

/// A pair of timestamp queries and the buffers that bring them back.
struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
}

/// An adapter and device on Vulkan, with wgpu's uncaught errors collected
/// instead of panicking (its default), so that a bad upload becomes a
/// `RenderError` and the renderer stays usable.
pub(super) struct Context {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Whether 32-bit float textures can be filtered (filtered sampling).
    pub filterable: bool,
    /// Whether 16-bit normalised textures exist: 16-bit volumes keep two
    /// bytes a voxel where they do, and take four (as floats) where not.
    pub norm16: bool,
    /// Every volume paged, in bricks of this many texels a side, where
    /// the renderer was told so; otherwise only volumes longer than the
    /// adapter's 3D texture limit or past the memory budget are paged.
    pub brick_texels: Option<u32>,
    /// Bytes the scene's volume textures (and brick pools) may take
    /// together, where set.
    pub memory_budget: Option<u64>,
    /// What the driver was found to allocate: set where it refused a
    /// scene's textures for lack of memory, halved at each refusal.
    pub driver_budget: Option<u64>,
    errors: Arc<Mutex<Vec<String>>>,
    timestamps: Option<Timestamps>,
}

/// Mesa's implicit device-selection layer looks for a Wayland display
/// while it enumerates GPUs. With no `XDG_RUNTIME_DIR` there can be none,
/// and libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set"
/// for every enumeration, on the host's stderr. Its only job is to put the
/// display's GPU first; the adapter is chosen here by type, so the layer is
/// turned off in exactly that case, once, before the first instance, and
/// never where the host set either variable itself.
fn quiet_device_select() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let has = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !has("XDG_RUNTIME_DIR") && std::env::var_os("NODEVICE_SELECT").is_none() {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    });
}

impl Context {
    /// The memory budget volumes are laid out for: the one set, or what
    /// the driver was found to allocate, whichever is smaller.
    pub fn budget(&self) -> Option<u64> {
        match (self.memory_budget, self.driver_budget) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// The adapter `new` would open, without a device: what it is.
    pub fn probe() -> Result<wgpu::AdapterInfo, RenderError> {
        Ok(Self::adapter()?.get_info())
    }

    fn adapter() -> Result<wgpu::Adapter, RenderError> {
        quiet_device_select();
        // Vulkan only: GL's 1D textures and array layers are unreliable,
        // and CI runs lavapipe, which is Vulkan.
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            flags: wgpu::InstanceFlags::empty().with_env(),
            // A texture past 90% of the memory budget the driver reports
            // (VK_EXT_memory_budget) is refused as out of memory before
            // it is allocated, instead of failing, or losing the device,
            // as it is.
            memory_budget_thresholds: wgpu::MemoryBudgetThresholds {
                for_resource_creation: Some(90),
                for_device_loss: None,
            },
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))
    }

    pub fn new() -> Result<Self, RenderError> {
        let adapter = Self::adapter()?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        // Software Vulkan (lavapipe) offers timestamps, but writes the end
        // of a compute pass before its threads finish: a 10 ms ray cast
        // reads as 0.0 ms there. Its passes are timed by the host's clock.
        let timing = match info.device_type {
            wgpu::DeviceType::Cpu => wgpu::Features::empty(),
            _ => adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        };
        // Filtered sampling reads R32Float volumes and RGBA32Float tables
        // through a linear sampler.
        let features = timing
            | (adapter.features()
                & (wgpu::Features::FLOAT32_FILTERABLE | wgpu::Features::TEXTURE_FORMAT_16BIT_NORM));
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("caveray"),
            required_limits: limits.clone(),
            required_features: features,
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
        let timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY).then(|| {
            let buffer = |label, usage| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: 16,
                    usage,
                    mapped_at_creation: false,
                })
            };
            use wgpu::BufferUsages as U;
            Timestamps {
                set: device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                }),
                resolve: buffer("timestamps", U::QUERY_RESOLVE | U::COPY_SRC),
                read: buffer("timestamps read-back", U::MAP_READ | U::COPY_DST),
                period: f64::from(queue.get_timestamp_period()),
            }
        });
        Ok(Self {
            device,
            queue,
            info,
            brick_texels: None,
            memory_budget: None,
            driver_budget: None,
            limits,
            filterable: features.contains(wgpu::Features::FLOAT32_FILTERABLE),
            norm16: features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM),
            errors,
            timestamps,
        })
    }

    pub fn pass_clock(&self) -> PassClock {
        match self.timestamps {
            Some(_) => PassClock::GpuTimestamps,
            None => PassClock::CpuClock,
        }
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
    /// pass's milliseconds by `pass_clock()`.
    pub fn dispatch(
        &self,
        pipeline: &wgpu::ComputePipeline,
        groups: &[&wgpu::BindGroup],
        workgroups: [u32; 3],
    ) -> Result<f64, RenderError> {
        let pass = Pass {
            pipeline,
            groups,
            band: None,
        };
        self.dispatch_bands(&pass, &[workgroups], Watch::new(&AtomicBool::new(false)))
    }

    /// Runs `pass` once per entry of `bands` (band i's workgroups, and its
    /// band group bound at dynamic offset i * BAND_STRIDE), each its own
    /// submission with at most two in flight, and gives up with
    /// `RenderError::Stopped` between bands once the watch's stop flag is
    /// set. Counts each band into the watch's progress once the GPU has
    /// finished it (the caller announced them). Returns the milliseconds
    /// from the first band's start to the last's end.
    pub fn dispatch_bands(
        &self,
        pass: &Pass<'_>,
        bands: &[[u32; 3]],
        watch: Watch,
    ) -> Result<f64, RenderError> {
        let start = std::time::Instant::now();
        let mut in_flight: Option<wgpu::SubmissionIndex> = None;
        for (i, workgroups) in bands.iter().enumerate() {
            if watch.stopped() {
                self.wait()?;
                return Err(RenderError::Stopped);
            }
            let (first, last) = (i == 0, i + 1 == bands.len());
            let mut encoder = self.device.create_command_encoder(&Default::default());
            {
                let timestamp_writes =
                    self.timestamps
                        .as_ref()
                        .map(|t| wgpu::ComputePassTimestampWrites {
                            query_set: &t.set,
                            beginning_of_pass_write_index: first.then_some(0),
                            end_of_pass_write_index: last.then_some(1),
                        });
                let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: None,
                    timestamp_writes,
                });
                compute.set_pipeline(pass.pipeline);
                for (g, group) in pass.groups.iter().enumerate() {
                    compute.set_bind_group(g as u32, *group, &[]);
                }
                if let Some(band) = pass.band {
                    let offset = i as u32 * BAND_STRIDE;
                    compute.set_bind_group(pass.groups.len() as u32, band, &[offset]);
                }
                compute.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
            }
            if let (true, Some(t)) = (last, &self.timestamps) {
                encoder.resolve_query_set(&t.set, 0..2, &t.resolve, 0);
                encoder.copy_buffer_to_buffer(&t.resolve, 0, &t.read, 0, None);
            }
            let submitted = self.queue.submit([encoder.finish()]);
            // Keep the GPU fed: wait for the band before this one only.
            if let Some(previous) = in_flight.replace(submitted) {
                self.device
                    .poll(wgpu::PollType::Wait {
                        submission_index: Some(previous),
                        timeout: None,
                    })
                    .map_err(|e| RenderError::Gpu(e.to_string()))?;
                watch.advance(1);
            }
        }
        self.wait()?;
        if !bands.is_empty() {
            watch.advance(1);
        }
        let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        self.check()?;
        match &self.timestamps {
            None => Ok(cpu_ms),
            Some(t) => {
                let bytes = self.read(&t.read, 16)?;
                let tick = |i: usize| {
                    let mut word = [0u8; 8];
                    word.copy_from_slice(&bytes[8 * i..8 * i + 8]);
                    u64::from_le_bytes(word)
                };
                Ok(tick(1).saturating_sub(tick(0)) as f64 * t.period * 1e-6)
            }
        }
    }

    /// Fails, before touching the GPU, if the frame exceeds what this
    /// adapter allows.
    pub fn check_frame(&self, desc: &FrameDesc) -> Result<(), RenderError> {
        let limits = &self.limits;
        let pixels = u64::from(desc.size.x) * u64::from(desc.size.y);
        let bytes = pixels * desc.color.bytes_per_pixel();
        let max_bytes = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let groups = desc.size.max_element().div_ceil(WORKGROUP);
        let reason = if bytes > max_bytes {
            Some(format!(
                "its {bytes} bytes of color exceed the largest storage buffer ({max_bytes} bytes)"
            ))
        } else if groups > limits.max_compute_workgroups_per_dimension {
            Some(format!(
                "{groups} workgroups per side exceed the limit of {}",
                limits.max_compute_workgroups_per_dimension
            ))
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(RenderError::FrameTooLarge {
                size: [desc.size.x, desc.size.y],
                reason,
                adapter: self.info.name.clone(),
            });
        }
        Ok(())
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

/// A pass's resource asked for before the pass made it.
pub(super) fn unprepared() -> RenderError {
    RenderError::Gpu("internal: render target used before it was made".into())
}
