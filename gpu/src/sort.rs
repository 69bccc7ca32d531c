//! The sort by pixel that MLAB's order-dependent insert needs (submission order kept within a
//! pixel): a counting sort on the CPU ([`Sort::Cpu`]) or a bitonic sort on the GPU
//! ([`Sort::Gpu`], [`wgsl::SORT`]). Both give the same order, hence the same bytes.

use bytemuck::Zeroable;

use crate::device::{Device, STORAGE, whole};
use crate::error::GpuError;
use crate::fragment::GpuFragment;
use crate::plan::{Band, key_count};
use crate::wgsl;

/// Where the compositor sorts the fragments by pixel (submission order kept within a pixel, the
/// order MLAB's order-dependent insert needs). Both give the same order, hence the same bytes.
/// A new [`Compositor`](crate::Compositor) sorts on the GPU, except on a software adapter
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

crate::device::uniform! {
    /// The host side of `sort.wgsl`'s uniform (binding 0, `SortParams`): the bytes uploaded for
    /// each dispatch, so it repeats the WGSL struct field for field (the test
    /// `the_uniforms_match_the_wgsl_structs` compares the two).
    SortParams {
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
        pad0: u32,
        pad1: u32,
    }
}

/// A band's fragments on the GPU, sorted: with keys ([`Sort::Gpu`]),
/// `keys[offsets[p] .. offsets[p + 1]]` are pixel `p`'s `(pixel, index into fragments)` pairs
/// in submission order; without ([`Sort::Cpu`]), the fragments were uploaded in that order and
/// `fragments[offsets[p] .. offsets[p + 1]]` are pixel `p`'s.
pub(crate) struct Sorted {
    pub(crate) fragments: wgpu::Buffer,
    pub(crate) keys: Option<wgpu::Buffer>,
    pub(crate) offsets: wgpu::Buffer,
    /// The most fragments of one pixel.
    pub(crate) most: u32,
    /// [`Sort::Cpu`]: the indices of the band's fragments in pixel order.
    order: Vec<u32>,
}

impl Sorted {
    /// The indices of the band's fragments in pixel order (read back from the GPU for
    /// [`Sort::Gpu`]).
    pub(crate) fn order(self, device: &Device, band: &Band) -> Result<Vec<u32>, GpuError> {
        Ok(match &self.keys {
            Some(keys) => {
                let keys = device.download(keys, 8 * band.fragments.len() as u64)?;
                keys.chunks_exact(2).map(|k| k[1]).collect()
            }
            None => self.order,
        })
    }
}

/// The stable counting sort by the band's stored pixel: `(offsets, order, most)`, pixel `p`'s
/// fragments being `order[offsets[p] .. offsets[p + 1]]` (indices into the band's fragments,
/// in submission order), `most` the most fragments of one pixel.
fn counting_sort(band: &Band) -> (Vec<u32>, Vec<u32>, u32) {
    let mut offsets = vec![0u32; band.pixels as usize + 1];
    for f in band.fragments.iter() {
        offsets[band.local(f) as usize + 1] += 1;
    }
    let most = offsets.iter().copied().max().unwrap_or(0);
    for p in 0..band.pixels as usize {
        offsets[p + 1] += offsets[p];
    }
    let mut cursor = offsets.clone();
    let mut order = vec![0u32; band.fragments.len()];
    for (index, f) in (0u32..).zip(band.fragments.iter()) {
        let p = band.local(f) as usize;
        order[cursor[p] as usize] = index;
        cursor[p] += 1;
    }
    (offsets, order, most)
}

/// One dispatch of the GPU sort: `(k, j, entry point, invocations)`.
type Step = (u32, u32, usize, u32);

/// The dispatches of the GPU sort of `size` keys (a power of two) and `pixels` stored pixels:
/// the keys (`sort_init`), every bitonic step (`sort_step`; `k = 2, 4, .., size`,
/// `j = k / 2, .., 1`), the offsets (`sort_offsets_of`).
fn steps(size: u32, pixels: u32) -> Vec<Step> {
    let mut steps = vec![(0, 0, 0, size)];
    let mut k = 2;
    while k <= size {
        let mut j = k / 2;
        while j > 0 {
            steps.push((k, j, 1, size / 2));
            j /= 2;
        }
        k *= 2;
    }
    steps.push((0, 0, 2, pixels + 1));
    steps
}

/// The compiled [`wgsl::SORT`] and the choice of [`Sort`].
#[derive(Debug)]
pub(crate) struct Sorter {
    /// `sort_init`, `sort_step`, `sort_offsets_of` of `sort.wgsl`.
    pipelines: [wgpu::ComputePipeline; 3],
    pub(crate) sort: Sort,
    /// Compare the index after the pixel (false only in the test of an unstable sort).
    pub(crate) stable: bool,
}

impl Sorter {
    /// Compiles [`wgsl::SORT`] (inside the caller's error scope).
    pub(crate) fn new(device: &Device, sort: Sort) -> Sorter {
        let entries = ["sort_init", "sort_step", "sort_offsets_of"];
        Sorter {
            pipelines: device.pipelines("mlab-gpu sort", wgsl::SORT, entries),
            sort,
            stable: true,
        }
    }

    /// Uploads a band's fragments and sorts them by pixel ([`Sort`]).
    pub(crate) fn sorted(&self, device: &Device, band: &Band) -> Result<Sorted, GpuError> {
        // A binding may not be empty: a band without fragments binds one unused fragment.
        let placeholder = [GpuFragment::zeroed()];
        let upload = |fragments: &[GpuFragment]| {
            let words = if fragments.is_empty() { &placeholder } else { fragments };
            device.init("fragments", bytemuck::cast_slice(words), STORAGE)
        };
        if self.sort == Sort::Cpu {
            let (offsets, order, most) = counting_sort(band);
            // The fragments themselves in pixel order: the composite reads them in sequence.
            let in_order: Vec<GpuFragment> = order.iter().map(|&i| band.fragments[i as usize]).collect();
            return device.scoped(
                || Sorted {
                    fragments: upload(&in_order),
                    keys: None,
                    offsets: device.init("offsets", bytemuck::cast_slice(&offsets), STORAGE),
                    most,
                    order,
                },
                GpuError::Device,
            );
        }
        let (most, sorted) = device.scoped(
            || self.gpu_sort(device, band, upload(&band.fragments)),
            GpuError::Device,
        )?;
        let most = device.read(&most)?[0];
        Ok(Sorted { most, ..sorted })
    }

    /// Records and submits the GPU sort of a band whose `fragments` are uploaded: the sorted
    /// band (`most` not yet known) and the buffer `most` will be read from.
    fn gpu_sort(&self, device: &Device, band: &Band, fragments: wgpu::Buffer) -> (wgpu::Buffer, Sorted) {
        let n = band.fragments.len() as u32;
        let size = key_count(u64::from(n)) as u32;
        let keys = device.empty("keys", 8 * u64::from(size), STORAGE);
        let offsets = device.empty("offsets", 4 * (u64::from(band.pixels) + 1), STORAGE);
        // Created zeroed (wgpu clears new buffers).
        let most = device.empty("most", 4, STORAGE);
        let most_back = device.readback("most readback", 4);
        let steps = steps(size, band.pixels);
        // One uniform buffer holds the parameters of every dispatch.
        let stride = device.uniform_align as usize;
        let mut uniform = vec![0u8; stride * steps.len()];
        for (at, &(k, j, _, invocations)) in steps.iter().enumerate() {
            let params = SortParams {
                count: n,
                size,
                pitch: device.grid(invocations).2,
                k,
                j,
                width: band.width,
                line: band.line,
                first: band.first,
                pixels: band.pixels,
                stable: u32::from(self.stable),
                pad0: 0,
                pad1: 0,
            };
            uniform[at * stride..at * stride + size_of::<SortParams>()].copy_from_slice(bytemuck::bytes_of(&params));
        }
        let uniform = device.init("sort params", &uniform, wgpu::BufferUsages::UNIFORM);
        let mut encoder = device.encoder();
        for (at, &(_, _, pipeline, invocations)) in steps.iter().enumerate() {
            let params = wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &uniform,
                    offset: (at * stride) as u64,
                    size: wgpu::BufferSize::new(size_of::<SortParams>() as u64),
                }),
            };
            let entries = match at {
                0 => vec![params, whole(1, &fragments), whole(2, &keys)],
                _ if at + 1 == steps.len() => vec![params, whole(2, &keys), whole(3, &offsets), whole(4, &most)],
                _ => vec![params, whole(2, &keys)],
            };
            device.dispatch(
                &mut encoder,
                "mlab-gpu sort",
                &self.pipelines[pipeline],
                &entries,
                invocations,
            );
        }
        encoder.copy_buffer_to_buffer(&most, 0, &most_back, 0, 4);
        device.submit(encoder);
        let sorted = Sorted {
            fragments,
            keys: Some(keys),
            offsets,
            most: 0,
            order: Vec::new(),
        };
        (most_back, sorted)
    }
}

#[cfg(test)]
mod tests {
    use super::{counting_sort, steps};
    use crate::fragment::GpuFragment;
    use crate::plan::{Layout, Plan};
    use mlab::Layers;

    #[test]
    fn the_counting_sort_keeps_submission_order_within_a_pixel() {
        let at = |pixel| GpuFragment::new(pixel, [0.0; 4], 1.0);
        // 3 x 2 in spans: stored pixels 0..16, pixel 4 = (1, 1) is stored pixel 9.
        let frags = [at(4), at(0), at(4), at(2), at(0), at(4)];
        let plan = Plan::new(Layers::Mlab(1), Layout::Spans, 1 << 20, (3, 2), &frags)
            .expect("plan")
            .expect("stored");
        let (offsets, order, most) = counting_sort(&plan.band(&frags, plan.bands[0]));
        assert_eq!(order, [1, 4, 3, 0, 2, 5]);
        assert_eq!(most, 3);
        assert_eq!(offsets.len(), 17);
        assert_eq!((offsets[0], offsets[1], offsets[2], offsets[3]), (0, 2, 2, 3));
        assert_eq!((offsets[9], offsets[10], offsets[16]), (3, 6, 6));
    }

    #[test]
    fn the_bitonic_network_has_every_stage_and_distance() {
        // 8 keys: init, (2,1), (4,2), (4,1), (8,4), (8,2), (8,1), offsets.
        let s = steps(8, 5);
        let kj: Vec<(u32, u32)> = s[1..s.len() - 1].iter().map(|&(k, j, _, _)| (k, j)).collect();
        assert_eq!(kj, [(2, 1), (4, 2), (4, 1), (8, 4), (8, 2), (8, 1)]);
        assert_eq!((s[0].2, s[0].3), (0, 8));
        assert_eq!(s[s.len() - 1], (0, 0, 2, 6));
        assert!(s[1..s.len() - 1].iter().all(|&(_, _, e, n)| e == 1 && n == 4));
        assert_eq!(steps(1, 0), [(0, 0, 0, 1), (0, 0, 2, 1)]);
    }
}
