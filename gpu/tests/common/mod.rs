//! Shared by the GPU tests: the adapter (the tests are ignored without a driver, `gpu/build.rs`), a
//! deterministic generator and fragment streams.
#![allow(dead_code)]

use mlab_gpu::{Gpu, GpuFragment};
use wgpu::util::DeviceExt;

/// The compute pipeline `entry` of the WGSL `source`.
pub fn pipeline(gpu: &Gpu, source: String, entry: &str) -> wgpu::ComputePipeline {
    let device = gpu.device();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A 2-D dispatch of `items` invocations: (groups in x, groups in y), invocations per row.
pub fn grid(items: u32) -> ((u32, u32), u32) {
    let groups = items.div_ceil(64).max(1);
    let gx = groups.min(65535);
    ((gx, groups.div_ceil(gx)), gx * 64)
}

/// A buffer holding `words`.
pub fn buffer(gpu: &Gpu, words: &[u32], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device().create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(words),
        usage,
    })
}

/// `n` bright fragments into pixels 0, 1 and 2, every other one opaque, at 1000 depths: the
/// tails' colors, alpha and count saturate.
pub fn saturating(n: u32) -> Vec<GpuFragment> {
    (0..n)
        .map(|i| {
            GpuFragment::new(
                i % 3,
                [1.0, 0.5, 1.0, if i % 2 == 0 { 1.0 } else { 0.5 }],
                (i % 1000) as f32,
            )
        })
        .collect()
}

/// Run `pipeline` over `gx * gy` workgroups with bind group 0 = `inputs` (bindings `0..`), an
/// output storage buffer of `size` bytes, then `uniform`; read the output back as u32 words.
pub fn dispatch_words(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    inputs: &[&wgpu::Buffer],
    uniform: &wgpu::Buffer,
    (gx, gy): (u32, u32),
    size: u64,
) -> Vec<u32> {
    let device = gpu.device();
    let buffer = |usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage,
            mapped_at_creation: false,
        })
    };
    let out = buffer(wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
    let back = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
    let buffers: Vec<&wgpu::Buffer> = inputs.iter().copied().chain([&out, uniform]).collect();
    let entries: Vec<wgpu::BindGroupEntry> = (0u32..)
        .zip(&buffers)
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &back, 0, size);
    gpu.queue().submit([encoder.finish()]);
    back.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    let view = back.slice(..).get_mapped_range().expect("mapped");
    view.chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// The GPU. A test that calls this is built `#[ignore]`d where `gpu/build.rs` found no Vulkan
/// driver (not under `CI=true`), so `cargo test` reports it as ignored, never as passed; where a
/// driver was found, or under `CI=true`, a missing adapter fails the test. The `Option` lets a
/// test read `let Some(gpu) = gpu(..) else { return }`; it is always `Some`.
pub fn gpu(test: &str) -> Option<Gpu> {
    match Gpu::new() {
        Ok(gpu) => Some(gpu),
        Err(e) if std::env::var("CI").is_ok_and(|v| v == "true") => {
            panic!("{test}: CI=true and no GPU adapter: {e} (install mesa-vulkan-drivers libvulkan1)")
        }
        Err(e) => panic!(
            "{test}: a Vulkan driver was found when mlab-gpu was built, but no adapter: {e} \
             (repair the driver, or build with MLAB_GPU_TESTS=skip to ignore the GPU tests)"
        ),
    }
}

/// SplitMix64: deterministic, seedable, no dependency.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next() >> 32) * u64::from(n)) >> 32) as u32
    }

    /// Uniform in [0, 1) with 24 bits.
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// A value in [0, 1] from a mix of regimes: uniform, exact bytes k / 255, tiny and
    /// subnormal values, 0, -0 and 1, and any f32 bit pattern in [0, 1].
    pub fn value(&mut self) -> f32 {
        match self.below(8) {
            0..=2 => self.unit(),
            3 => self.below(256) as f32 / 255.0,
            4 => self.unit() * 1e-3,
            5 => f32::from_bits(self.below(0x0080_0000)), // subnormal
            6 => [0.0, -0.0, 1.0, 0.5 / 255.0, 16.0 / 255.0][self.below(5) as usize],
            _ => f32::from_bits(self.below(1.0f32.to_bits() + 1)),
        }
    }

    /// Alpha in [0, 1]: faint (below 16 / 255, dithered by Unbiased), mid, opaque, zero.
    pub fn alpha(&mut self) -> f32 {
        match self.below(6) {
            0 | 1 => self.unit() * (17.0 / 255.0), // faint and the threshold around 16 / 255
            2 => 1.0,
            3 => 0.0,
            _ => self.value(),
        }
    }

    /// A finite depth: few distinct values (coplanar fragments), random, extremes.
    pub fn depth(&mut self) -> f32 {
        match self.below(6) {
            0 | 1 => self.below(4) as f32,
            2 => self.unit() * 100.0 - 10.0,
            3 => [0.0, -0.0, f32::MAX, -f32::MAX, f32::MIN_POSITIVE, 1e-45, -1e-45][self.below(7) as usize],
            _ => {
                // any finite bit pattern
                let b = self.next() as u32;
                let f = f32::from_bits(b);
                if f.is_finite() { f } else { 1.0 }
            }
        }
    }

    /// A valid premultiplied fragment for `pixel`: color usually at most alpha, sometimes
    /// additive (color above alpha, up to 1).
    pub fn fragment(&mut self, pixel: u32) -> GpuFragment {
        let a = self.alpha();
        let additive = self.below(8) == 0;
        let c = |r: &mut Rng| if additive { r.value() } else { r.value() * a };
        let rgba = [c(self), c(self), c(self), a];
        GpuFragment::new(pixel, rgba, self.depth())
    }

    /// `frags` with stable keys (`GpuFragment::with_key`) on most of them: few distinct keys
    /// (primitive ids shared by many fragments and pixels), the extremes 0 and `u32::MAX`, a
    /// `keyed` flag other than 1 (any value but 0 means keyed), and some left without a key (the
    /// content key), so that one stream mixes both.
    pub fn keyed(&mut self, frags: Vec<GpuFragment>) -> Vec<GpuFragment> {
        frags
            .into_iter()
            .map(|f| match self.below(8) {
                0 => f,
                1 => f.with_key([0, u32::MAX, 0x8000_0000][self.below(3) as usize]),
                2 => GpuFragment {
                    key: self.next() as u32,
                    keyed: 1 + self.below(u32::MAX),
                    ..f
                },
                _ => f.with_key(self.below(64)),
            })
            .collect()
    }

    /// A fragment for a random pixel of `pixels`.
    pub fn fragment_in(&mut self, pixels: u32) -> GpuFragment {
        let p = self.below(pixels);
        self.fragment(p)
    }

    /// Two streams of `count` fragments into `pixels`: opaque ones in random order (a
    /// z-buffer), then coplanar ones (all at depth 1).
    pub fn opaque_and_coplanar(&mut self, pixels: u32, count: usize) -> [Vec<GpuFragment>; 2] {
        let opaque = self.edited(pixels, count, |_, f| f.rgba[3] = 1.0);
        [opaque, self.edited(pixels, count, |_, f| f.depth = 1.0)]
    }

    /// `count` fragments for random pixels of `pixels`, fragment `i` changed by `edit(i, f)`:
    /// the adversarial streams of the tests (opaque, coplanar, additive, ...).
    pub fn edited(&mut self, pixels: u32, count: usize, edit: impl Fn(usize, &mut GpuFragment)) -> Vec<GpuFragment> {
        (0..count)
            .map(|i| {
                let mut f = self.fragment_in(pixels);
                edit(i, &mut f);
                f
            })
            .collect()
    }
}
