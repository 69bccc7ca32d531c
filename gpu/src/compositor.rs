//! The wgpu compositor: fragments in submission order in, the kernel's storage words out.

use crate::cpu::{slots, validate};
use crate::{Arith, GpuError, wgsl};
use bytemuck::{Pod, Zeroable};
use mlab::{Background, Layers};
use wgpu::util::DeviceExt;

/// One fragment for [`Compositor::composite`]: its pixel (`y * width + x`), premultiplied linear
/// `[R, G, B, A]` and depth, as [`mlab::Fragment::premultiplied_rgba`] takes them (validated the
/// same way).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuFragment {
    /// `y * width + x`.
    pub pixel: u32,
    /// Premultiplied color and alpha.
    pub rgba: [f32; 4],
    /// Depth (smaller = nearer).
    pub depth: f32,
}

/// How the pixels' slots are laid out in the returned words (the kernel's arrangements).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// [`mlab::PixelMajor`]: pixel `p` owns slots `p * R .. (p + 1) * R` (`R` = `M`, or `K + 1`
    /// with the tail last), as `MlabFramebuffer` and `HybridFramebuffer` store them.
    PixelMajor,
    /// [`mlab::Spans`]: slot `j` of pixel `(x, y)` is `((y * ceil(w / 8) + x / 8) * R + j) * 8 +
    /// x % 8`, padding lanes empty, as `DynFramebuffer` and the span framebuffers store them.
    Spans,
}

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
    /// ([`Compositor::max_binding_bytes`]).
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

/// Bytes per fragment on the GPU: the bits of R, G, B, alpha, depth.
const FRAGMENT_BYTES: u64 = 20;
/// Fragments per pixel per dispatch (`COMPOSITE_CHUNK` in `composite.wgsl`: lavapipe ends an
/// invocation's loops after 65,535 iterations in all).
const CHUNK: u32 = 32768;
/// Invocations per workgroup (`@workgroup_size(64)` in `composite.wgsl`).
const WORKGROUP: u32 = 64;
/// The most bytes one storage binding may hold: WebGPU's default
/// `maxStorageBufferBindingSize` (128 MiB).
const DEFAULT_BINDING_BYTES: u64 = 128 << 20;

/// 128 MiB, or less where the device's storage binding or buffer size limit is lower.
fn binding_limit(limits: &wgpu::Limits) -> u64 {
    DEFAULT_BINDING_BYTES
        .min(limits.max_storage_buffer_binding_size)
        .min(limits.max_buffer_size)
}

/// The compute pipeline of one method, size and arithmetic (the text of [`wgsl::compositor`]).
#[derive(Debug)]
pub struct Compositor {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
    /// The integer RGBA8 resolve (every method and size has one).
    resolve: Option<wgpu::ComputePipeline>,
    layers: Layers,
    layout: Layout,
    source: String,
    max_binding: u64,
    max_groups: u32,
}

/// The uniform of `composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    pixels: u32,
    pitch: u32,
    spans: u32,
    first: u32,
    width: u32,
    line: u32,
    pad: [u32; 2],
    background: [u32; 4],
}

/// The background channels as the kernel's integer resolve quantizes them
/// (`docs/layout.md`, "Integer resolve": `b` clamped to `[0, 1]`, NaN to 0, then
/// `floor(b * 32640 + 0.5)` in f32, a multiply and then an add), with `1` in the fourth slot for
/// an opaque background; `[0, 0, 0, 0]` for [`Background::Transparent`]. Computed on the CPU:
/// the shader receives integers. (An FMA would not change this step: every f32 in `[0, 1]`
/// gives the same value fused, `docs/gpu.md`.)
pub fn background_q15(background: Background) -> [u32; 4] {
    match background {
        Background::Opaque(c) => {
            let q = |b: f32| {
                let b = if b > 1.0 { 1.0 } else { b };
                let b = if b >= 0.0 { b } else { 0.0 };
                #[expect(
                    clippy::cast_possible_truncation,
                    clippy::cast_sign_loss,
                    reason = "b in [0, 1]: b * 32640 + 0.5 in [0.5, 32640.5], truncated as specified"
                )]
                let v = (b * 32640.0 + 0.5) as u32;
                v
            };
            [q(c.x), q(c.y), q(c.z), 1]
        }
        Background::Transparent => [0; 4],
    }
}

/// One band's dispatch input.
struct Band<'a> {
    offsets: &'a [u32],
    fragments: &'a [u32],
    pixels: u32,
    width: u32,
    line: u32,
    background: Option<[u32; 4]>,
}

impl Compositor {
    /// Compiles [`wgsl::compositor`]`(layers, arith)` on `gpu`.
    pub fn new(gpu: &Gpu, layers: Layers, arith: Arith, layout: Layout) -> Result<Compositor, GpuError> {
        let source = wgsl::compositor(layers, arith)?;
        let device = &gpu.device;
        let (pipeline, resolve) = scoped(
            device,
            || {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("mlab-gpu composite"),
                    source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
                });
                let entry = |name| {
                    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(name),
                        layout: None,
                        module: &module,
                        entry_point: Some(name),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                };
                let resolve = Some(entry("resolve"));
                (entry("composite"), resolve)
            },
            GpuError::Shader,
        )?;
        let limits = device.limits();
        Ok(Compositor {
            device: device.clone(),
            queue: gpu.queue.clone(),
            pipeline,
            resolve,
            layers,
            layout,
            source,
            max_binding: binding_limit(&limits),
            max_groups: limits.max_compute_workgroups_per_dimension,
        })
    }

    /// The WGSL this compositor compiled (equal to [`wgsl::compositor`] for its method, size
    /// and arithmetic).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The most bytes one storage binding holds: 128 MiB (or less where the device allows
    /// less). Frames whose rows or fragments need more are composited in bands of lines.
    pub fn max_binding_bytes(&self) -> u64 {
        self.max_binding
    }

    /// A lower binding limit (at least 1 KiB; never above the device's): smaller bands, less
    /// memory at a time. For tests of the band split, and for sharing a small GPU.
    pub fn set_max_binding_bytes(&mut self, bytes: u64) {
        self.max_binding = bytes.clamp(1024, binding_limit(&self.device.limits()));
    }

    /// Composites `fragments` (in submission order) into a cleared `width x height`
    /// framebuffer and returns its storage as [`mlab::Row::words`] pairs in `self`'s
    /// [`Layout`]: the bytes [`crate::cpu::composite`] gives for the same input.
    ///
    /// Every fragment is validated first (pixel inside the frame, [`mlab::Fragment`]'s
    /// checks); nothing is sent to the GPU unless all are valid. The CPU sorts the fragments by
    /// pixel (a stable counting sort: submission order kept within a pixel); the GPU runs one
    /// invocation per stored pixel. Memory: see `docs/gpu.md`.
    pub fn composite(&self, width: u32, height: u32, fragments: &[GpuFragment]) -> Result<Vec<u32>, GpuError> {
        self.run(width, height, fragments, None).map(|(words, _)| words)
    }

    /// [`composite`](Self::composite), then the kernel's integer RGBA8 resolve on the GPU
    /// (`docs/layout.md`, "Integer resolve" for MLAB, "Integer resolve of HT" for HT: what
    /// `Framebuffer::resolve_rgba8` writes) over `background`: the storage words and the
    /// image, `width * height` pixels, row-major; the bytes of [`crate::cpu::resolve_rgba8`].
    pub fn composite_rgba8(
        &self,
        width: u32,
        height: u32,
        fragments: &[GpuFragment],
        background: Background,
    ) -> Result<(Vec<u32>, Vec<[u8; 4]>), GpuError> {
        if self.resolve.is_none() {
            return Err(GpuError::NoIntegerResolve(self.layers));
        }
        let (words, image) = self.run(width, height, fragments, Some(background_q15(background)))?;
        Ok((words, image.into_iter().map(u32::to_le_bytes).collect()))
    }

    fn run(
        &self,
        width: u32,
        height: u32,
        fragments: &[GpuFragment],
        background: Option<[u32; 4]>,
    ) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
        let too_large = GpuError::FrameTooLarge { width, height };
        let pixels = width.checked_mul(height).ok_or(too_large.clone())?;
        // Stored pixels per line: spans pad each line to a multiple of 8.
        let pitch = match self.layout {
            Layout::PixelMajor => width,
            Layout::Spans => width.div_ceil(8).checked_mul(8).ok_or(too_large.clone())?,
        };
        let stored = pitch.checked_mul(height).ok_or(too_large.clone())?;
        if stored >= u32::MAX / 8 {
            return Err(too_large);
        }
        if u32::try_from(fragments.len()).is_err() {
            return Err(GpuError::TooManyFragments { count: fragments.len() });
        }
        if stored == 0 {
            // Nothing stored; still every fragment must be valid (none can be: no pixel).
            return match fragments.first() {
                Some(f) => validate(0, f, 0).map(|_| (Vec::new(), Vec::new())),
                None => Ok((Vec::new(), Vec::new())),
            };
        }
        // Stable counting sort by stored pixel, after validation.
        let mut offsets = vec![0u32; stored as usize + 1];
        let mut keys = Vec::with_capacity(fragments.len());
        for (index, f) in fragments.iter().enumerate() {
            validate(index, f, pixels)?;
            let key = (f.pixel / width) * pitch + f.pixel % width;
            keys.push(key);
            offsets[key as usize + 1] += 1;
        }
        for i in 0..stored as usize {
            offsets[i + 1] += offsets[i];
        }
        let mut cursor = offsets.clone();
        let mut sorted = vec![0u32; fragments.len() * 5];
        for (f, &key) in fragments.iter().zip(&keys) {
            let at = cursor[key as usize] as usize;
            cursor[key as usize] += 1;
            let [r, g, b, a] = f.rgba.map(f32::to_bits);
            sorted[5 * at..5 * at + 5].copy_from_slice(&[r, g, b, a, f.depth.to_bits()]);
        }
        // Bands of whole lines, each within the binding limit.
        let slots = slots(self.layers) as u64;
        let line_bytes = u64::from(pitch) * slots * 8;
        let mut words = Vec::with_capacity((u64::from(stored) * slots * 2) as usize);
        let mut image = Vec::new();
        let mut y0 = 0u32;
        while y0 < height {
            let mut y1 = y0;
            while y1 < height {
                let rows = (u64::from(y1 - y0) + 1) * line_bytes;
                let frags = u64::from(offsets[((y1 + 1) * pitch) as usize] - offsets[(y0 * pitch) as usize]);
                if rows > self.max_binding || frags * FRAGMENT_BYTES > self.max_binding {
                    break;
                }
                y1 += 1;
            }
            if y1 == y0 {
                let frags = u64::from(offsets[((y0 + 1) * pitch) as usize] - offsets[(y0 * pitch) as usize]);
                return Err(GpuError::LineTooLarge {
                    y: y0,
                    bytes: line_bytes.max(frags * FRAGMENT_BYTES),
                    limit: self.max_binding,
                });
            }
            let (p0, p1) = ((y0 * pitch) as usize, (y1 * pitch) as usize);
            let base = offsets[p0];
            let band_offsets: Vec<u32> = offsets[p0..=p1].iter().map(|o| o - base).collect();
            let band_fragments = &sorted[5 * base as usize..5 * offsets[p1] as usize];
            let (w, i) = self.band(&Band {
                offsets: &band_offsets,
                fragments: band_fragments,
                pixels: (p1 - p0) as u32,
                width,
                line: pitch,
                background,
            })?;
            words.extend(w);
            image.extend(i);
            y0 = y1;
        }
        Ok((words, image))
    }

    /// One dispatch over `pixels` stored pixels.
    fn band(&self, band: &Band) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
        let Band {
            offsets,
            fragments,
            pixels,
            width,
            line,
            background,
        } = *band;
        let device = &self.device;
        let groups = pixels.div_ceil(WORKGROUP);
        let gx = groups.clamp(1, self.max_groups);
        let gy = groups.div_ceil(gx).max(1);
        // Dispatches: one per CHUNK fragments of the most crowded pixel.
        let most = offsets.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
        let passes = most.div_ceil(CHUNK).max(1);
        let params = |pass: u32| Params {
            pixels,
            pitch: gx * WORKGROUP,
            spans: u32::from(self.layout == Layout::Spans),
            first: pass * CHUNK,
            width,
            line,
            pad: [0; 2],
            background: background.unwrap_or([0; 4]),
        };
        // RGBA8 pixels of the band: its lines times the width (at least one word: no empty
        // binding).
        let image_bytes = u64::from(pixels / line.max(1)) * u64::from(width) * 4;
        let out_bytes = u64::from(pixels) * slots(self.layers) as u64 * 8;
        // A binding may not be empty: a band without fragments binds one unused fragment.
        let placeholder = [0u32; 5];
        let fragments = if fragments.is_empty() {
            &placeholder[..]
        } else {
            fragments
        };
        let make = || {
            let init = |label, contents: &[u8], usage| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage,
                })
            };
            let offsets = init("offsets", bytemuck::cast_slice(offsets), wgpu::BufferUsages::STORAGE);
            let fragments = init(
                "fragments",
                bytemuck::cast_slice(fragments),
                wgpu::BufferUsages::STORAGE,
            );
            let rows = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("rows"),
                size: out_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: out_bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            for pass in 0..passes {
                let params = init("params", bytemuck::bytes_of(&params(pass)), wgpu::BufferUsages::UNIFORM);
                let entries = [&params, &offsets, &fragments, &rows];
                let entries: Vec<wgpu::BindGroupEntry> = (0u32..)
                    .zip(entries)
                    .map(|(binding, buffer)| wgpu::BindGroupEntry {
                        binding,
                        resource: buffer.as_entire_binding(),
                    })
                    .collect();
                let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("mlab-gpu composite"),
                    layout: &self.pipeline.get_bind_group_layout(0),
                    entries: &entries,
                });
                // One compute pass per dispatch: a later one reads the rows the earlier stored.
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("mlab-gpu composite"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            let image = match (&self.resolve, background) {
                (Some(resolve), Some(_)) => {
                    let params = init("params", bytemuck::bytes_of(&params(0)), wgpu::BufferUsages::UNIFORM);
                    let image = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("image"),
                        size: image_bytes.max(4),
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                        mapped_at_creation: false,
                    });
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("mlab-gpu resolve"),
                        layout: &resolve.get_bind_group_layout(0),
                        entries: &[
                            wgpu::BindGroupEntry {
                                binding: 0,
                                resource: params.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: 3,
                                resource: rows.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: 4,
                                resource: image.as_entire_binding(),
                            },
                        ],
                    });
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("mlab-gpu resolve"),
                        timestamp_writes: None,
                    });
                    pass.set_pipeline(resolve);
                    pass.set_bind_group(0, &bind, &[]);
                    pass.dispatch_workgroups(gx, gy, 1);
                    drop(pass);
                    let back = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("image readback"),
                        size: image_bytes.max(4),
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    encoder.copy_buffer_to_buffer(&image, 0, &back, 0, image_bytes.max(4));
                    Some(back)
                }
                _ => None,
            };
            encoder.copy_buffer_to_buffer(&rows, 0, &readback, 0, out_bytes);
            self.queue.submit([encoder.finish()]);
            (readback, image)
        };
        let (readback, image) = scoped(device, make, GpuError::Device)?;
        let words = read(device, &readback)?;
        let image = match image {
            Some(buffer) => {
                let mut words = read(device, &buffer)?;
                words.truncate((image_bytes / 4) as usize);
                words
            }
            None => Vec::new(),
        };
        Ok((words, image))
    }
}

/// The words of a `MAP_READ` buffer, after the queue's work.
fn read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        // The receiver waits below; a send error cannot happen while it does.
        let _ = tx.send(r);
    });
    device
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

/// Runs `f` inside validation and out-of-memory error scopes: the first error is returned
/// (wrapped by `wrap`) instead of reaching wgpu's uncaptured-error handler, which panics.
fn scoped<T>(device: &wgpu::Device, f: impl FnOnce() -> T, wrap: fn(String) -> GpuError) -> Result<T, GpuError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        Some(e) => Err(wrap(e.to_string())),
        None => Ok(value),
    }
}
