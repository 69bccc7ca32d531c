//! The wgpu plumbing: the device ([`Gpu`]), buffers, dispatches, error scopes and readback.
//! Nothing here knows the compositor's method or its bindings.

use crate::error::GpuError;
use wgpu::util::DeviceExt;

/// A wgpu device on the first Vulkan adapter, with the WebGPU default limits.
#[derive(Debug)]
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
}

impl Gpu {
    /// The first Vulkan adapter (high-performance preference, software adapters included:
    /// lavapipe where there is no GPU), with `wgpu::Limits::default()`.
    pub fn new() -> Result<Gpu, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("mlab-gpu"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::default(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::RequestDevice(e.to_string()))?;
        Ok(Gpu { device, queue, info })
    }

    /// A renderer's own device and queue (any backend), with its adapter's info: the
    /// compositor then shares them. The device's limits decide the bands
    /// ([`Compositor::max_binding_bytes`](crate::Compositor::max_binding_bytes)).
    pub fn with_device(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo) -> Gpu {
        Gpu { device, queue, info }
    }

    /// The adapter: name, driver, driver info, backend.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The device (for a renderer that shares it).
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }
}

/// A `#[repr(C)]` mirror of a WGSL uniform struct (every field `pub(crate)`), and in tests its
/// fields' names and byte offsets (`FIELDS`), which a test compares with the WGSL text.
macro_rules! uniform {
    ($(#[$meta:meta])* $name:ident { $($field:ident: $ty:ty,)* }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        pub(crate) struct $name {
            $(pub(crate) $field: $ty,)*
        }

        #[cfg(test)]
        impl $name {
            /// Each field's name and offset in bytes, in order.
            pub(crate) const FIELDS: &[(&str, usize)] = &[$((stringify!($field), core::mem::offset_of!($name, $field)),)*];
        }
    };
}
pub(crate) use uniform;

/// Invocations per workgroup (`@workgroup_size(64)` in `composite.wgsl` and `sort.wgsl`).
const WORKGROUP: u32 = 64;

/// The most bytes one storage binding may hold: WebGPU's default
/// `maxStorageBufferBindingSize` (128 MiB).
const DEFAULT_BINDING_BYTES: u64 = 128 << 20;

/// A storage buffer the compositor writes and copies out.
pub(crate) const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

/// The device and queue a compositor dispatches on, with the limits its dispatches need.
#[derive(Debug)]
pub(crate) struct Device {
    device: wgpu::Device,
    queue: wgpu::Queue,
    max_groups: u32,
    /// The stride of the entries of one uniform buffer read at several offsets: the device's
    /// `min_uniform_buffer_offset_alignment`, at least 64.
    pub(crate) uniform_align: u64,
}

impl Device {
    /// `gpu`'s device and queue (shared, not copied).
    pub(crate) fn new(gpu: &Gpu) -> Device {
        let limits = gpu.device.limits();
        Device {
            device: gpu.device.clone(),
            queue: gpu.queue.clone(),
            max_groups: limits.max_compute_workgroups_per_dimension,
            uniform_align: u64::from(limits.min_uniform_buffer_offset_alignment).max(64),
        }
    }

    /// 128 MiB, or less where the device's storage binding or buffer size limit is lower.
    pub(crate) fn binding_limit(&self) -> u64 {
        let limits = self.device.limits();
        DEFAULT_BINDING_BYTES
            .min(limits.max_storage_buffer_binding_size)
            .min(limits.max_buffer_size)
    }

    /// The compute pipelines `entries` of the WGSL module `source` (validation errors are
    /// caught by the caller's [`scoped`](Self::scoped)).
    pub(crate) fn pipelines<const N: usize>(
        &self,
        label: &str,
        source: &str,
        entries: [&str; N],
    ) -> [wgpu::ComputePipeline; N] {
        let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        entries.map(|name| {
            self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: None,
                module: &module,
                entry_point: Some(name),
                compilation_options: Default::default(),
                cache: None,
            })
        })
    }

    /// `(gx, gy, invocations per row)` of a 2-D dispatch of at least `invocations`.
    pub(crate) fn grid(&self, invocations: u32) -> (u32, u32, u32) {
        let groups = invocations.div_ceil(WORKGROUP);
        let gx = groups.clamp(1, self.max_groups);
        (gx, groups.div_ceil(gx).max(1), gx * WORKGROUP)
    }

    /// A buffer holding `contents`.
    pub(crate) fn init(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    }

    /// A buffer of `size` bytes, zeroed (wgpu clears new buffers).
    pub(crate) fn empty(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }

    /// A buffer of `size` bytes to copy results into and [`read`](Self::read).
    pub(crate) fn readback(&self, label: &str, size: u64) -> wgpu::Buffer {
        self.empty(label, size, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST)
    }

    /// A command encoder.
    pub(crate) fn encoder(&self) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None })
    }

    /// Submits `encoder`'s commands.
    pub(crate) fn submit(&self, encoder: wgpu::CommandEncoder) {
        self.queue.submit([encoder.finish()]);
    }

    /// One compute pass of `pipeline` over at least `invocations` invocations ([`grid`](Self::grid)),
    /// with `entries` bound to group 0. One pass per dispatch: a later dispatch reads what an
    /// earlier one wrote.
    pub(crate) fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        entries: &[wgpu::BindGroupEntry],
        invocations: u32,
    ) {
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &pipeline.get_bind_group_layout(0),
            entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        let (gx, gy, _) = self.grid(invocations);
        pass.dispatch_workgroups(gx, gy, 1);
    }

    /// Runs `f` inside validation and out-of-memory error scopes: the first error is returned
    /// (wrapped by `wrap`) instead of reaching wgpu's uncaptured-error handler, which panics.
    pub(crate) fn scoped<T>(&self, f: impl FnOnce() -> T, wrap: fn(String) -> GpuError) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        match v.or(o) {
            Some(e) => Err(wrap(e.to_string())),
            None => Ok(value),
        }
    }

    /// The words of a `MAP_READ` buffer, after the queue's work.
    pub(crate) fn read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            // The receiver waits below; a send error cannot happen while it does.
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Device(e.to_string()))?
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let view = slice.get_mapped_range().map_err(|e| GpuError::Device(e.to_string()))?;
        let words = view
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        drop(view);
        buffer.unmap();
        Ok(words)
    }

    /// The first `bytes` of a `STORAGE | COPY_SRC` buffer, as words.
    pub(crate) fn download(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u32>, GpuError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let back = self.scoped(
            || {
                let back = self.readback("readback", bytes);
                let mut encoder = self.encoder();
                encoder.copy_buffer_to_buffer(buffer, 0, &back, 0, bytes);
                self.submit(encoder);
                back
            },
            GpuError::Device,
        )?;
        self.read(&back)
    }
}

/// `buffer`, whole, at `binding`.
pub(crate) fn whole(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}
