//! One band's passes: the composite dispatches (one per [`chunk`] fragments of the most crowded
//! pixel), then with a background the integer RGBA8 resolve, then the readback.

use mlab::{Background, Layers};

use crate::device::{Device, STORAGE, whole};
use crate::error::GpuError;
use crate::plan::{Band, Layout};
use crate::sort::Sorted;

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
    let r = layers.rows_per_pixel() as u32;
    (LOOP_LIMIT - 2 * r) / (r + 1)
}

crate::device::uniform! {
    /// The host side of `composite.wgsl`'s uniform (binding 0, `CompositeParams`): the bytes
    /// uploaded for each dispatch, so it repeats the WGSL struct field for field (the test
    /// `the_uniforms_match_the_wgsl_structs` compares the two).
    Params {
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
}

/// The background channels as the kernel's integer resolve quantizes them
/// ([`Background::integer_channels`]: `docs/layout.md`, "Integer resolve"), with `1` in the
/// fourth slot for an opaque background; `[0, 0, 0, 0]` for [`Background::Transparent`].
/// Computed on the CPU: the shader receives integers. (An FMA would not change this step: every
/// f32 in `[0, 1]` gives the same value fused, `docs/gpu.md`.)
pub fn background_q15(background: Background) -> [u32; 4] {
    match background.integer_channels() {
        Some([r, g, b]) => [r, g, b, 1],
        None => [0; 4],
    }
}

/// The compiled composite and resolve entry points of one method, size and arithmetic.
#[derive(Debug)]
pub(crate) struct Passes {
    composite: wgpu::ComputePipeline,
    /// The integer RGBA8 resolve (every method and size has one).
    resolve: wgpu::ComputePipeline,
    layers: Layers,
    layout: Layout,
}

impl Passes {
    /// Compiles `source` ([`crate::wgsl::compositor`]`(layers, ..)`, inside the caller's error
    /// scope).
    pub(crate) fn new(device: &Device, source: &str, layers: Layers, layout: Layout) -> Passes {
        let [composite, resolve] = device.pipelines("mlab-gpu composite", source, ["composite", "resolve"]);
        Passes {
            composite,
            resolve,
            layers,
            layout,
        }
    }

    /// The storage words of one sorted band and, with a `background` ([`crate::background_q15`]),
    /// its RGBA8 image (its lines times the width, as words).
    pub(crate) fn run(
        &self,
        device: &Device,
        band: &Band,
        sorted: &Sorted,
        background: Option<[u32; 4]>,
    ) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
        let &Band {
            pixels, width, line, ..
        } = band;
        // RGBA8 pixels of the band: its lines times the width.
        let image_bytes = u64::from(pixels / line.max(1)) * u64::from(width) * 4;
        let out_bytes = u64::from(pixels) * self.layers.rows_per_pixel() as u64 * 8;
        let params = Params {
            pixels,
            pitch: device.grid(pixels).2,
            spans: u32::from(self.layout == Layout::Spans),
            first: 0,
            width,
            line,
            sorted: u32::from(sorted.keys.is_none()),
            chunk: chunk(self.layers),
            background: background.unwrap_or([0; 4]),
        };
        let (readback, image) = device.scoped(
            || {
                let mut encoder = device.encoder();
                let rows = self.composite(device, &mut encoder, sorted, params, out_bytes);
                // At least one word: no empty binding.
                let image = background.map(|_| self.resolve(device, &mut encoder, &rows, params, image_bytes.max(4)));
                let readback = device.readback("readback", out_bytes);
                encoder.copy_buffer_to_buffer(&rows, 0, &readback, 0, out_bytes);
                device.submit(encoder);
                (readback, image)
            },
            GpuError::Device,
        )?;
        let words = device.read(&readback)?;
        let image = match image {
            Some(buffer) => {
                let mut words = device.read(&buffer)?;
                words.truncate((image_bytes / 4) as usize);
                words
            }
            None => Vec::new(),
        };
        Ok((words, image))
    }

    /// Records the composite dispatches into a new rows buffer of `bytes` and returns it.
    fn composite(
        &self,
        device: &Device,
        encoder: &mut wgpu::CommandEncoder,
        sorted: &Sorted,
        params: Params,
        bytes: u64,
    ) -> wgpu::Buffer {
        // Sort::Cpu: binding 5 is not read, but a binding may not be empty.
        let no_keys = device.init("no keys", &[0; 8], wgpu::BufferUsages::STORAGE);
        let rows = device.empty("rows", bytes, STORAGE);
        let pixels = params.pixels;
        // One dispatch per `chunk` fragments of the most crowded pixel.
        let passes = sorted.most.div_ceil(params.chunk).max(1);
        for pass in 0..passes {
            let params = Params {
                first: pass * params.chunk,
                ..params
            };
            let params = device.init("params", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM);
            let entries = [
                whole(0, &params),
                whole(1, &sorted.offsets),
                whole(2, &sorted.fragments),
                whole(3, &rows),
                whole(5, sorted.keys.as_ref().unwrap_or(&no_keys)),
            ];
            device.dispatch(encoder, "mlab-gpu composite", &self.composite, &entries, pixels);
        }
        rows
    }

    /// Records the resolve of `rows` into a new image buffer of `bytes`, copied into a
    /// readback buffer, which it returns.
    fn resolve(
        &self,
        device: &Device,
        encoder: &mut wgpu::CommandEncoder,
        rows: &wgpu::Buffer,
        params: Params,
        bytes: u64,
    ) -> wgpu::Buffer {
        let pixels = params.pixels;
        let params = device.init("params", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM);
        let image = device.empty("image", bytes, STORAGE);
        let entries = [whole(0, &params), whole(3, rows), whole(4, &image)];
        device.dispatch(encoder, "mlab-gpu resolve", &self.resolve, &entries, pixels);
        let back = device.readback("image readback", bytes);
        encoder.copy_buffer_to_buffer(&image, 0, &back, 0, bytes);
        back
    }
}

#[cfg(test)]
mod tests {
    use super::{LOOP_LIMIT, chunk};
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
            let r = layers.rows_per_pixel() as u32;
            let iterations = |c: u32| 2 * r + c * (r + 1);
            assert!(iterations(chunk(layers)) <= LOOP_LIMIT, "{layers:?}");
            assert!(iterations(chunk(layers) + 1) > LOOP_LIMIT, "{layers:?}");
        }
        assert_eq!(chunk(Layers::Mlab(1)), 32_766);
        assert_eq!(chunk(Layers::Mlab(8)), 7_279);
        assert_eq!(chunk(Layers::Hybrid(8)), 6_551);
    }
}
