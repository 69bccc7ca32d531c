//! The wgpu compositor: fragments in submission order in, the kernel's storage words out.

use crate::cpu::{slots, validate};
use crate::{Arith, GpuError, wgsl};
use bytemuck::{Pod, Zeroable};
use mlab::{Background, Layers};
use wgpu::util::DeviceExt;

/// One fragment for [`Compositor::composite`]: its pixel (`y * width + x`), premultiplied linear
/// `[R, G, B, A]` and depth, as [`mlab::Fragment::premultiplied_rgba`] takes them (validated the
/// same way), and optionally a stable key ([`mlab::Fragment::with_key`]: the primitive's id,
/// which seeds [`mlab::Unbiased`]'s dithers so that they do not re-roll from frame to frame).
///
/// The layout is what the GPU reads (8 words, `composite.wgsl`), so a renderer that writes
/// fragments from a shader writes the same words: `keyed` is a `u32` flag rather than an
/// `Option` for that reason. Build one with [`GpuFragment::new`] and
/// [`with_key`](GpuFragment::with_key).
///
/// ```
/// use mlab_gpu::GpuFragment;
/// let f = GpuFragment::new(5, [0.02, 0.0, 0.0, 0.02], 2.0).with_key(42);
/// assert_eq!(f.key(), Some(42));
/// assert_eq!(GpuFragment::new(5, [0.0; 4], 2.0).key(), None); // the content key seeds it
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuFragment {
    /// `y * width + x`: where it is inserted, and the pixel id of its hash
    /// ([`mlab::fragment_hash`]; the kernel's `Framebuffer::pixel_id`).
    pub pixel: u32,
    /// Premultiplied color and alpha.
    pub rgba: [f32; 4],
    /// Depth (smaller = nearer).
    pub depth: f32,
    /// The stable key, read only when `keyed` is not 0.
    pub key: u32,
    /// Not 0: `key` is the fragment's stable key ([`mlab::Fragment::with_key`]); 0: it has
    /// none, and its dithers are seeded with its content key (the XOR of the bits of its five
    /// f32, [`mlab::Fragment::hash`]), which changes with its depth.
    pub keyed: u32,
}

impl GpuFragment {
    /// A fragment without a stable key.
    pub const fn new(pixel: u32, rgba: [f32; 4], depth: f32) -> GpuFragment {
        GpuFragment {
            pixel,
            rgba,
            depth,
            key: 0,
            keyed: 0,
        }
    }

    /// This fragment with the stable key `key` (as [`mlab::Fragment::with_key`]).
    #[must_use]
    pub const fn with_key(self, key: u32) -> GpuFragment {
        GpuFragment { key, keyed: 1, ..self }
    }

    /// The stable key, if it has one (`keyed` not 0).
    pub const fn key(&self) -> Option<u32> {
        if self.keyed != 0 { Some(self.key) } else { None }
    }
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

/// Loop iterations one invocation may run in all on lavapipe (llvmpipe's gallivm loop limiter:
/// one counter per shader function, every iteration of every loop, inner loops included unless
/// the compiler unrolled them; past it the loops silently end).
const LOOP_LIMIT: u32 = 65_535;

/// Fragments per pixel per dispatch for `layers` (`chunk` in `composite.wgsl`): as many as keep
/// the loops of one `composite` invocation within [`LOOP_LIMIT`] even when no loop is unrolled.
/// With `R` slots (`M`, or `K + 1`), an invocation loads and stores its slots (at most `2 R`
/// iterations) and runs, per fragment, one iteration of the fragment loop and at most `R` of the
/// insert's (Listing 1: `M - 1`, Listing 2: `K`; the merges and tail adds have no loop).
/// `R = 1`: 32,766; `R = 9` (HT 8): 6,551.
const fn chunk(layers: Layers) -> u32 {
    let r = slots(layers) as u32;
    (LOOP_LIMIT - 2 * r) / (r + 1)
}

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

/// Where the compositor sorts the fragments by pixel (submission order kept within a pixel, the
/// order MLAB's order-dependent insert needs). Both give the same order, hence the same bytes.
/// A new [`Compositor`] sorts on the GPU, except on a software adapter
/// (`wgpu::DeviceType::Cpu`, such as lavapipe), where it sorts on the CPU: there the GPU sort
/// runs on the same cores and measured 17-19x slower (`docs/gpu.md`, "Throughput").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sort {
    /// On the GPU: a bitonic sort of `(pixel, submission index)` pairs, unique keys, so the
    /// order is the stable one ([`wgsl::SORT`]); offsets by a binary search per pixel. The
    /// CPU only validates, counts fragments per line (for the bands) and uploads the
    /// fragments as given.
    Gpu,
    /// On the CPU: a stable counting sort by pixel; the GPU receives the fragments in that order
    /// and the offsets (host memory: 36 bytes per fragment).
    /// Faster on a software driver such as lavapipe, which runs the GPU's work on the same CPU
    /// cores (`docs/gpu.md`, "Throughput").
    Cpu,
}

/// The compute pipelines of one method, size and arithmetic (the text of [`wgsl::compositor`])
/// and of the sort ([`wgsl::SORT`]).
#[derive(Debug)]
pub struct Compositor {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::ComputePipeline,
    /// The integer RGBA8 resolve (every method and size has one).
    resolve: Option<wgpu::ComputePipeline>,
    /// `sort_init`, `sort_step`, `sort_offsets_of` of `sort.wgsl`.
    sort_pipelines: [wgpu::ComputePipeline; 3],
    sort: Sort,
    /// Compare the index after the pixel (false only in the test of an unstable sort).
    stable: bool,
    layers: Layers,
    layout: Layout,
    source: String,
    max_binding: u64,
    max_groups: u32,
    uniform_align: u64,
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
    sorted: u32,
    chunk: u32,
    background: [u32; 4],
}

/// The uniform of `sort.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SortParams {
    count: u32,
    size: u32,
    pitch: u32,
    k: u32,
    j: u32,
    width: u32,
    line: u32,
    first: u32,
    pixels: u32,
    stable: u32,
    pad: [u32; 2],
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

/// One band of whole lines: its fragments in submission order and where it lies.
struct Band<'a> {
    fragments: &'a [GpuFragment],
    /// The band's first stored pixel.
    first: u32,
    /// Its stored pixels.
    pixels: u32,
    width: u32,
    line: u32,
}

/// A band's fragments on the GPU, sorted: with keys ([`Sort::Gpu`]),
/// `keys[offsets[p] .. offsets[p + 1]]` are pixel `p`'s `(pixel, index into fragments)` pairs
/// in submission order; without ([`Sort::Cpu`]), the fragments were uploaded in that order and
/// `fragments[offsets[p] .. offsets[p + 1]]` are pixel `p`'s.
struct Sorted {
    fragments: wgpu::Buffer,
    keys: Option<wgpu::Buffer>,
    offsets: wgpu::Buffer,
    /// The most fragments of one pixel.
    most: u32,
    /// [`Sort::Cpu`]: the indices of the band's fragments in pixel order.
    order: Vec<u32>,
}

/// What [`Compositor::run`] returns besides the order of the fragments.
#[derive(Clone, Copy)]
enum Out {
    /// The rows, and the RGBA8 image over the background when there is one.
    Rows(Option<[u32; 4]>),
    /// The order only.
    Order,
}

/// What [`Compositor::run`] returns: the storage words and the RGBA8 image, or the order.
#[derive(Default)]
struct Output {
    words: Vec<u32>,
    image: Vec<u32>,
    order: Vec<u32>,
}

/// Padded key count for `n` fragments: a power of two, at least 1.
fn key_count(n: u64) -> u64 {
    n.next_power_of_two().max(1)
}

impl Compositor {
    /// Compiles [`wgsl::compositor`]`(layers, arith)` and [`wgsl::SORT`] on `gpu`; the sort is
    /// [`Sort::Gpu`].
    pub fn new(gpu: &Gpu, layers: Layers, arith: Arith, layout: Layout) -> Result<Compositor, GpuError> {
        let source = wgsl::compositor(layers, arith)?;
        let device = &gpu.device;
        let (pipeline, resolve, sort_pipelines) = scoped(
            device,
            || {
                let module = |label, text: &str| {
                    device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(label),
                        source: wgpu::ShaderSource::Wgsl(text.into()),
                    })
                };
                let composite = module("mlab-gpu composite", &source);
                let sort = module("mlab-gpu sort", wgsl::SORT);
                let entry = |module: &wgpu::ShaderModule, name| {
                    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(name),
                        layout: None,
                        module,
                        entry_point: Some(name),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                };
                let resolve = Some(entry(&composite, "resolve"));
                let sorts = ["sort_init", "sort_step", "sort_offsets_of"].map(|name| entry(&sort, name));
                (entry(&composite, "composite"), resolve, sorts)
            },
            GpuError::Shader,
        )?;
        let limits = device.limits();
        Ok(Compositor {
            device: device.clone(),
            queue: gpu.queue.clone(),
            pipeline,
            resolve,
            sort_pipelines,
            sort: if gpu.info.device_type == wgpu::DeviceType::Cpu {
                Sort::Cpu
            } else {
                Sort::Gpu
            },
            stable: true,
            layers,
            layout,
            source,
            max_binding: binding_limit(&limits),
            max_groups: limits.max_compute_workgroups_per_dimension,
            uniform_align: u64::from(limits.min_uniform_buffer_offset_alignment).max(64),
        })
    }

    /// The WGSL this compositor compiled (equal to [`wgsl::compositor`] for its method, size
    /// and arithmetic; the sort's is [`wgsl::SORT`]).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Where the fragments are sorted by pixel.
    pub fn sort(&self) -> Sort {
        self.sort
    }

    /// Sorts on the GPU ([`Sort::Gpu`]) or the CPU ([`Sort::Cpu`]): the same bytes. The
    /// default depends on the adapter ([`Sort`]).
    pub fn set_sort(&mut self, sort: Sort) {
        self.sort = sort;
    }

    /// Test only: with `false`, [`Sort::Gpu`] compares pixels alone (an unstable sort: the
    /// order within a pixel is the bitonic network's, not the submission order), so a test can
    /// show that its comparison detects an unstable sort. Never use it otherwise.
    #[doc(hidden)]
    pub fn set_stable_sort_for_tests(&mut self, stable: bool) {
        self.stable = stable;
    }

    /// The most bytes one storage binding holds: 128 MiB (or less where the device allows
    /// less). Frames whose buffers would need more are composited in bands of lines.
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
    /// checks); nothing is sent to the GPU unless all are valid. The fragments are sorted by
    /// pixel, submission order kept within a pixel (on the GPU by default, see [`Sort`]); the
    /// GPU then runs one invocation per stored pixel. Memory: see `docs/gpu.md`.
    pub fn composite(&self, width: u32, height: u32, fragments: &[GpuFragment]) -> Result<Vec<u32>, GpuError> {
        self.run(width, height, fragments, Out::Rows(None)).map(|o| o.words)
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
        let Output { words, image, .. } =
            self.run(width, height, fragments, Out::Rows(Some(background_q15(background))))?;
        Ok((words, image.into_iter().map(u32::to_le_bytes).collect()))
    }

    /// The order in which [`composite`](Self::composite) inserts `fragments`: their indices
    /// sorted by pixel, submission order kept within a pixel, as [`Self::sort`] computes it
    /// (read back from the GPU for [`Sort::Gpu`]); validated and banded as `composite`. For
    /// tests of the sort and for timing it alone.
    pub fn order(&self, width: u32, height: u32, fragments: &[GpuFragment]) -> Result<Vec<u32>, GpuError> {
        self.run(width, height, fragments, Out::Order).map(|o| o.order)
    }

    /// Bytes of the largest binding of a band of `pixels` stored pixels and `n` fragments: its
    /// rows, offsets, fragments (32 bytes each) or sort keys (8 bytes per padded key).
    fn band_bytes(&self, pixels: u64, n: u64) -> u64 {
        let rows = pixels * slots(self.layers) as u64 * 8;
        rows.max(4 * (pixels + 1))
            .max(n * size_of::<GpuFragment>() as u64)
            .max(8 * key_count(n))
    }

    /// Validates, bands, sorts, and then composites or returns the order.
    fn run(&self, width: u32, height: u32, fragments: &[GpuFragment], out: Out) -> Result<Output, GpuError> {
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
                Some(f) => validate(0, f, 0).map(|_| Default::default()),
                None => Ok(Default::default()),
            };
        }
        // Validation, and the fragments of each line (for the bands).
        let mut lines = vec![0u32; height as usize];
        for (index, f) in fragments.iter().enumerate() {
            validate(index, f, pixels)?;
            lines[(f.pixel / width) as usize] += 1;
        }
        // Bands of whole lines, each binding within the limit.
        let mut bands = Vec::new();
        let mut y0 = 0u32;
        while y0 < height {
            let (mut y1, mut n) = (y0, 0u64);
            while y1 < height {
                let more = n + u64::from(lines[y1 as usize]);
                if self.band_bytes(u64::from(y1 - y0 + 1) * u64::from(pitch), more) > self.max_binding {
                    break;
                }
                (y1, n) = (y1 + 1, more);
            }
            if y1 == y0 {
                return Err(GpuError::LineTooLarge {
                    y: y0,
                    bytes: self.band_bytes(u64::from(pitch), u64::from(lines[y0 as usize])),
                    limit: self.max_binding,
                });
            }
            bands.push((y0, y1));
            y0 = y1;
        }
        let slots = slots(self.layers) as u64;
        let mut words = Vec::with_capacity(if matches!(out, Out::Rows(_)) {
            (u64::from(stored) * slots * 2) as usize
        } else {
            0
        });
        let (mut image, mut order) = (Vec::new(), Vec::new());
        for &(y0, y1) in &bands {
            // One band: the input as given; several: each band's fragments copied out, in order,
            // with their indices in the input.
            let (own, global): (Vec<GpuFragment>, Vec<u32>) = if bands.len() == 1 {
                Default::default()
            } else {
                (0u32..)
                    .zip(fragments)
                    .filter(|(_, f)| (y0..y1).contains(&(f.pixel / width)))
                    .map(|(i, f)| (*f, i))
                    .unzip()
            };
            let band = Band {
                fragments: if bands.len() == 1 { fragments } else { &own },
                first: y0 * pitch,
                pixels: (y1 - y0) * pitch,
                width,
                line: pitch,
            };
            let sorted = self.sorted(&band)?;
            match out {
                Out::Rows(background) => {
                    let (w, i) = self.composite_band(&band, &sorted, background)?;
                    words.extend(w);
                    image.extend(i);
                }
                Out::Order => {
                    let local = match &sorted.keys {
                        Some(keys) => {
                            let keys = self.download(keys, 8 * band.fragments.len() as u64)?;
                            keys.chunks_exact(2).map(|k| k[1]).collect()
                        }
                        None => sorted.order,
                    };
                    let local = local.into_iter();
                    if bands.len() == 1 {
                        order.extend(local);
                    } else {
                        order.extend(local.map(|i| global[i as usize]));
                    }
                }
            }
        }
        Ok(Output { words, image, order })
    }

    /// `(gx, gy, invocations per row)` of a 2-D dispatch of at least `invocations`.
    fn grid(&self, invocations: u32) -> (u32, u32, u32) {
        let groups = invocations.div_ceil(WORKGROUP);
        let gx = groups.clamp(1, self.max_groups);
        (gx, groups.div_ceil(gx).max(1), gx * WORKGROUP)
    }

    /// Uploads a band's fragments and sorts them by pixel ([`Sort`]).
    fn sorted(&self, band: &Band) -> Result<Sorted, GpuError> {
        let device = &self.device;
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let n = band.fragments.len() as u32;
        // A binding may not be empty: a band without fragments binds one unused fragment.
        let placeholder = [GpuFragment::zeroed()];
        let words: &[GpuFragment] = if n == 0 { &placeholder } else { band.fragments };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        if self.sort == Sort::Cpu {
            // Stable counting sort by the band's stored pixel.
            let local = |f: &GpuFragment| (f.pixel / band.width) * band.line + f.pixel % band.width - band.first;
            let mut offsets = vec![0u32; band.pixels as usize + 1];
            for f in band.fragments {
                offsets[local(f) as usize + 1] += 1;
            }
            let most = offsets.iter().copied().max().unwrap_or(0);
            for p in 0..band.pixels as usize {
                offsets[p + 1] += offsets[p];
            }
            let mut cursor = offsets.clone();
            let mut order = vec![0u32; n as usize];
            for (index, f) in (0u32..).zip(band.fragments) {
                let p = local(f) as usize;
                order[cursor[p] as usize] = index;
                cursor[p] += 1;
            }
            drop(cursor);
            // The fragments themselves in pixel order: the composite reads them in sequence.
            let in_order: Vec<GpuFragment> = order.iter().map(|&i| band.fragments[i as usize]).collect();
            let words: &[GpuFragment] = if n == 0 { &placeholder } else { &in_order };
            return scoped(
                device,
                || Sorted {
                    fragments: init("fragments", bytemuck::cast_slice(words), storage),
                    keys: None,
                    offsets: init("offsets", bytemuck::cast_slice(&offsets), storage),
                    most,
                    order,
                },
                GpuError::Device,
            );
        }
        let size = key_count(u64::from(n)) as u32;
        let (most_buffer, most_back, sorted) = scoped(
            device,
            || {
                let empty = |label, size, usage| {
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size,
                        usage,
                        mapped_at_creation: false,
                    })
                };
                let fragments = init("fragments", bytemuck::cast_slice(words), storage);
                let keys = empty("keys", 8 * u64::from(size), storage);
                let offsets = empty("offsets", 4 * (u64::from(band.pixels) + 1), storage);
                // Created zeroed (wgpu clears new buffers).
                let most = empty("most", 4, storage);
                let most_back = empty(
                    "most readback",
                    4,
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                );
                // Dispatches: the keys, every bitonic step (k = 2, 4, .., size; j = k / 2, .., 1),
                // the offsets. One uniform buffer holds all their parameters.
                let mut steps = vec![(0u32, 0u32, 0usize, size)];
                let mut k = 2;
                while k <= size {
                    let mut j = k / 2;
                    while j > 0 {
                        steps.push((k, j, 1, size / 2));
                        j /= 2;
                    }
                    k *= 2;
                }
                steps.push((0, 0, 2, band.pixels + 1));
                let stride = self.uniform_align as usize;
                let mut uniform = vec![0u8; stride * steps.len()];
                for (at, &(k, j, _, invocations)) in steps.iter().enumerate() {
                    let params = SortParams {
                        count: n,
                        size,
                        pitch: self.grid(invocations).2,
                        k,
                        j,
                        width: band.width,
                        line: band.line,
                        first: band.first,
                        pixels: band.pixels,
                        stable: u32::from(self.stable),
                        pad: [0; 2],
                    };
                    uniform[at * stride..at * stride + size_of::<SortParams>()]
                        .copy_from_slice(bytemuck::bytes_of(&params));
                }
                let uniform = init("sort params", &uniform, wgpu::BufferUsages::UNIFORM);
                let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                for (at, &(_, _, pipeline, invocations)) in steps.iter().enumerate() {
                    let pipeline = &self.sort_pipelines[pipeline];
                    let params = wgpu::BufferBinding {
                        buffer: &uniform,
                        offset: (at * stride) as u64,
                        size: wgpu::BufferSize::new(size_of::<SortParams>() as u64),
                    };
                    let buffers: &[(u32, &wgpu::Buffer)] = match at {
                        0 => &[(1, &fragments), (2, &keys)],
                        _ if at + 1 == steps.len() => &[(2, &keys), (3, &offsets), (4, &most)],
                        _ => &[(2, &keys)],
                    };
                    let mut entries = vec![wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(params),
                    }];
                    entries.extend(buffers.iter().map(|&(binding, buffer)| wgpu::BindGroupEntry {
                        binding,
                        resource: buffer.as_entire_binding(),
                    }));
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("mlab-gpu sort"),
                        layout: &pipeline.get_bind_group_layout(0),
                        entries: &entries,
                    });
                    // One compute pass per dispatch: each step reads what the previous wrote.
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("mlab-gpu sort"),
                        timestamp_writes: None,
                    });
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, &bind, &[]);
                    let (gx, gy, _) = self.grid(invocations);
                    pass.dispatch_workgroups(gx, gy, 1);
                }
                encoder.copy_buffer_to_buffer(&most, 0, &most_back, 0, 4);
                self.queue.submit([encoder.finish()]);
                (
                    most,
                    most_back,
                    Sorted {
                        fragments,
                        keys: Some(keys),
                        offsets,
                        most: 0,
                        order: Vec::new(),
                    },
                )
            },
            GpuError::Device,
        )?;
        let most = read(device, &most_back)?[0];
        drop(most_buffer);
        Ok(Sorted { most, ..sorted })
    }

    /// The first `bytes` of a `STORAGE | COPY_SRC` buffer, as words.
    fn download(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u32>, GpuError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let back = scoped(
            &self.device,
            || {
                let back = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("readback"),
                    size: bytes,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut encoder = self
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                encoder.copy_buffer_to_buffer(buffer, 0, &back, 0, bytes);
                self.queue.submit([encoder.finish()]);
                back
            },
            GpuError::Device,
        )?;
        read(&self.device, &back)
    }

    /// The composite dispatches of one sorted band (then its resolve, with a background).
    fn composite_band(
        &self,
        band: &Band,
        sorted: &Sorted,
        background: Option<[u32; 4]>,
    ) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
        let &Band {
            pixels, width, line, ..
        } = band;
        let device = &self.device;
        let (gx, gy, pitch) = self.grid(pixels);
        // Dispatches: one per `chunk` fragments of the most crowded pixel.
        let chunk = chunk(self.layers);
        let passes = sorted.most.div_ceil(chunk).max(1);
        let params = |pass: u32| Params {
            pixels,
            pitch,
            spans: u32::from(self.layout == Layout::Spans),
            first: pass * chunk,
            width,
            line,
            sorted: u32::from(sorted.keys.is_none()),
            chunk,
            background: background.unwrap_or([0; 4]),
        };
        // RGBA8 pixels of the band: its lines times the width (at least one word: no empty
        // binding).
        let image_bytes = u64::from(pixels / line.max(1)) * u64::from(width) * 4;
        let out_bytes = u64::from(pixels) * slots(self.layers) as u64 * 8;
        let make = || {
            let init = |label, contents: &[u8], usage| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage,
                })
            };
            // Sort::Cpu: binding 5 is not read, but a binding may not be empty.
            let no_keys = init("no keys", &[0; 8], wgpu::BufferUsages::STORAGE);
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
                let entries = [
                    (0, &params),
                    (1, &sorted.offsets),
                    (2, &sorted.fragments),
                    (3, &rows),
                    (5, sorted.keys.as_ref().unwrap_or(&no_keys)),
                ];
                let entries: Vec<wgpu::BindGroupEntry> = entries
                    .into_iter()
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

#[cfg(test)]
mod tests {
    use super::{LOOP_LIMIT, chunk};
    use crate::cpu::slots;
    use mlab::Layers;

    /// Every size's chunk keeps an invocation's loop iterations (2 R for the slots, R + 1 per
    /// fragment) within lavapipe's limit, and is the largest that does.
    #[test]
    fn the_chunk_of_every_size_fits_the_loop_limit() {
        let all = Layers::SIZES
            .into_iter()
            .map(Layers::Mlab)
            .chain(Layers::SIZES.into_iter().map(Layers::Hybrid));
        for layers in all {
            let r = slots(layers) as u32;
            let iterations = |c: u32| 2 * r + c * (r + 1);
            assert!(iterations(chunk(layers)) <= LOOP_LIMIT, "{layers:?}");
            assert!(iterations(chunk(layers) + 1) > LOOP_LIMIT, "{layers:?}");
        }
        assert_eq!(chunk(Layers::Mlab(1)), 32_766);
        assert_eq!(chunk(Layers::Mlab(8)), 7_279);
        assert_eq!(chunk(Layers::Hybrid(8)), 6_551);
    }
}
