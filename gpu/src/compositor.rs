//! The wgpu compositor: fragments in submission order in, the kernel's storage words out. Each
//! frame is planned on the CPU ([`crate::plan`]), then band by band sorted by pixel
//! ([`crate::sort`]) and composited ([`crate::pass`]).

use mlab::{ArithKind, Background, Layers};

use crate::device::{Device, Gpu};
use crate::error::GpuError;
use crate::fragment::GpuFragment;
use crate::pass::{Passes, background_q15};
use crate::plan::{Layout, Plan};
use crate::sort::{Sort, Sorter};
use crate::wgsl;

/// The compute pipelines of one method, size and arithmetic (the text of [`wgsl::compositor`])
/// and of the sort ([`wgsl::SORT`]).
#[derive(Debug)]
pub struct Compositor {
    device: Device,
    passes: Passes,
    sorter: Sorter,
    layers: Layers,
    layout: Layout,
    source: String,
    max_binding: u64,
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

impl Compositor {
    /// Compiles [`wgsl::compositor`]`(layers, arith)` and [`wgsl::SORT`] on `gpu`; the sort is
    /// [`Sort::Gpu`], or [`Sort::Cpu`] on a software adapter ([`Sort`]).
    pub fn new(gpu: &Gpu, layers: Layers, arith: ArithKind, layout: Layout) -> Result<Compositor, GpuError> {
        let source = wgsl::compositor(layers, arith)?;
        let device = Device::new(gpu);
        let sort = if gpu.adapter_info().device_type == wgpu::DeviceType::Cpu {
            Sort::Cpu
        } else {
            Sort::Gpu
        };
        let (passes, sorter) = device.scoped(
            || {
                let passes = Passes::new(&device, &source, layers, layout);
                (passes, Sorter::new(&device, sort))
            },
            GpuError::Shader,
        )?;
        let max_binding = device.binding_limit();
        Ok(Compositor {
            device,
            passes,
            sorter,
            layers,
            layout,
            source,
            max_binding,
        })
    }

    /// The WGSL this compositor compiled (equal to [`wgsl::compositor`] for its method, size
    /// and arithmetic; the sort's is [`wgsl::SORT`]).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Where the fragments are sorted by pixel.
    pub fn sort(&self) -> Sort {
        self.sorter.sort
    }

    /// Sorts on the GPU ([`Sort::Gpu`]) or the CPU ([`Sort::Cpu`]): the same bytes. The
    /// default depends on the adapter ([`Sort`]).
    pub fn set_sort(&mut self, sort: Sort) {
        self.sorter.sort = sort;
    }

    /// Test only: with `false`, [`Sort::Gpu`] compares pixels alone (an unstable sort: the
    /// order within a pixel is the bitonic network's, not the submission order), so a test can
    /// show that its comparison detects an unstable sort. Never use it otherwise.
    #[doc(hidden)]
    pub fn set_stable_sort_for_tests(&mut self, stable: bool) {
        self.sorter.stable = stable;
    }

    /// The most bytes one storage binding holds: 128 MiB (or less where the device allows
    /// less). Frames whose buffers would need more are composited in bands of lines.
    pub fn max_binding_bytes(&self) -> u64 {
        self.max_binding
    }

    /// A lower binding limit (at least 1 KiB; never above the device's): smaller bands, less
    /// memory at a time. For tests of the band split, and for sharing a small GPU.
    pub fn set_max_binding_bytes(&mut self, bytes: u64) {
        self.max_binding = bytes.clamp(1024, self.device.binding_limit());
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

    /// Plans the frame, then band by band sorts, and composites or returns the order.
    fn run(&self, width: u32, height: u32, fragments: &[GpuFragment], out: Out) -> Result<Output, GpuError> {
        let plan = Plan::new(self.layers, self.layout, self.max_binding, (width, height), fragments)?;
        let Some(plan) = plan else {
            return Ok(Output::default());
        };
        let mut output = Output::default();
        if matches!(out, Out::Rows(_)) {
            output
                .words
                .reserve(plan.stored as usize * self.layers.rows_per_pixel() * 2);
        }
        for &lines in &plan.bands {
            let band = plan.band(fragments, lines);
            let sorted = self.sorter.sorted(&self.device, &band)?;
            match out {
                Out::Rows(background) => {
                    let (words, image) = self.passes.run(&self.device, &band, &sorted, background)?;
                    output.words.extend(words);
                    output.image.extend(image);
                }
                Out::Order => {
                    let order = sorted.order(&self.device, &band)?;
                    output.order.extend(band.to_input(order));
                }
            }
        }
        Ok(output)
    }
}

#[cfg(test)]
mod tests {
    use crate::pass::Params;
    use crate::sort::SortParams;
    use crate::wgsl;
    use mlab::{ArithKind, Layers};

    /// The fields of `struct name` in `text` with their offsets and the struct's size, by
    /// WGSL's layout rules for the two types the uniforms use (`u32`: 4 bytes, aligned to 4;
    /// `vec4<u32>`: 16, aligned to 16).
    fn wgsl_layout(text: &str, name: &str) -> (Vec<(String, usize)>, usize) {
        let start = text.find(&format!("struct {name} {{")).expect("the struct");
        let body = &text[start..];
        let body = &body[body.find('{').expect("{") + 1..body.find('}').expect("}")];
        let (mut fields, mut offset, mut align) = (Vec::new(), 0usize, 4usize);
        for line in body.lines().map(|l| l.split("//").next().unwrap_or("").trim()) {
            let Some((field, ty)) = line.trim_end_matches(',').split_once(':') else {
                continue;
            };
            let (size, a) = match ty.trim() {
                "u32" => (4, 4),
                "vec4<u32>" => (16, 16),
                other => panic!("{name}.{field}: type {other} not covered"),
            };
            offset = offset.next_multiple_of(a);
            fields.push((field.trim().to_string(), offset));
            (offset, align) = (offset + size, align.max(a));
        }
        (fields, offset.next_multiple_of(align))
    }

    fn rust_fields(fields: &[(&str, usize)]) -> Vec<(String, usize)> {
        fields.iter().map(|&(n, o)| (n.to_string(), o)).collect()
    }

    /// The Rust mirrors of the two uniforms have the WGSL structs' fields, in order, at the
    /// same offsets, and the same size.
    #[test]
    fn the_uniforms_match_the_wgsl_structs() {
        let composite = wgsl::compositor(Layers::Mlab(1), ArithKind::Paper).expect("text");
        let (fields, size) = wgsl_layout(&composite, "CompositeParams");
        assert_eq!(fields, rust_fields(Params::FIELDS));
        assert_eq!(size, size_of::<Params>());
        let (fields, size) = wgsl_layout(wgsl::SORT, "SortParams");
        assert_eq!(fields, rust_fields(SortParams::FIELDS));
        assert_eq!(size, size_of::<SortParams>());
    }
}
