// The compositor's sort by pixel (mlab_gpu::Compositor, Sort::Gpu): a bitonic sort of
// (stored pixel, submission index) pairs. The keys are unique (the index), so the sorted order is
// the one order in which pixels ascend and, within a pixel, submission order is kept: a stable
// sort, which MLAB's order-dependent insert needs. No invocation loops more than 66 times in all
// (lavapipe ends an invocation's loops after 65,535 iterations): one compare-exchange per
// invocation per dispatch, two binary searches of at most 33 steps each per pixel for the offsets.
// Bindings (group 0; each entry point uses those it names):
//   0 uniform          SortParams
//   1 storage, read    fragments: array<u32>, SORT_WORDS words per fragment in submission
//                      order (the layout of mlab_gpu::GpuFragment: pixel first); only the
//                      pixel is read
//   2 storage, rw      keys: array<vec2<u32>>, `size` pairs (stored pixel of the band, index);
//                      entries count .. size are padding (0xffffffff, 0xffffffff), sorted last
//   3 storage, rw      offsets: array<u32>, pixels + 1 entries: pixel p's fragments are
//                      keys[offsets[p] .. offsets[p + 1]]
//   4 storage, rw      most: array<atomic<u32>, 1>, the largest fragment count of one pixel
//                      (0 before sort_offsets)
struct SortParams {
    // Fragments in this band, and the padded key count (a power of two, at least count and 1).
    count: u32,
    size: u32,
    // Invocations per row of the 2-D dispatch (workgroups in x times 64).
    pitch: u32,
    // sort_step: the bitonic stage (sequences of k keys, k a power of two) and the distance j
    // (k / 2, k / 4, .., 1) of the pairs compared.
    k: u32,
    j: u32,
    // Image width, stored pixels per line (the width, or 8 * ceil(width / 8) for spans), the
    // first stored pixel of the band, and the band's stored pixels.
    width: u32,
    line: u32,
    first: u32,
    pixels: u32,
    // 1: compare the index after the pixel (the stable sort). 0 only in a test that shows an
    // unstable sort changes the bytes.
    stable: u32,
    pad0: u32,
    pad1: u32,
}

// Words per fragment (mlab_gpu::GpuFragment: pixel, R, G, B, alpha, depth, key, keyed).
const SORT_WORDS: u32 = 8u;

const SORT_PAD: vec2<u32> = vec2<u32>(0xffffffffu, 0xffffffffu);

@group(0) @binding(0) var<uniform> sort_params: SortParams;
@group(0) @binding(1) var<storage, read> sort_fragments: array<u32>;
@group(0) @binding(2) var<storage, read_write> sort_keys: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read_write> sort_offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> sort_most: array<atomic<u32>, 1>;

fn sort_invocation(gid: vec3<u32>) -> u32 {
    return gid.y * sort_params.pitch + gid.x;
}

// One key per padded entry: (stored pixel - first, index) for a fragment, SORT_PAD after them.
@compute @workgroup_size(64)
fn sort_init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = sort_invocation(gid);
    if (i >= sort_params.size) {
        return;
    }
    if (i >= sort_params.count) {
        sort_keys[i] = SORT_PAD;
        return;
    }
    let pixel = sort_fragments[SORT_WORDS * i];
    let stored = (pixel / sort_params.width) * sort_params.line + pixel % sort_params.width;
    sort_keys[i] = vec2<u32>(stored - sort_params.first, i);
}

fn sort_less(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.x < b.x || (a.x == b.x && sort_params.stable != 0u && a.y < b.y);
}

// One compare-exchange of the bitonic network per invocation: invocation t (< size / 2) orders
// keys i and i + j, where i is t with a zero bit inserted at j; ascending where bit k of i is 0.
@compute @workgroup_size(64)
fn sort_step(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = sort_invocation(gid);
    if (t >= sort_params.size / 2u) {
        return;
    }
    let j = sort_params.j;
    let i = ((t & ~(j - 1u)) << 1u) | (t & (j - 1u));
    let l = i | j;
    let a = sort_keys[i];
    let b = sort_keys[l];
    let ascending = (i & sort_params.k) == 0u;
    if (select(sort_less(a, b), sort_less(b, a), ascending)) {
        sort_keys[i] = b;
        sort_keys[l] = a;
    }
}

// The first sorted position whose pixel is at least p (count if none).
fn sort_lower_bound(p: u32) -> u32 {
    var lo = 0u;
    var hi = sort_params.count;
    while (lo < hi) {
        let mid = lo + (hi - lo) / 2u;
        if (sort_keys[mid].x < p) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// offsets[p] for p in 0..=pixels, after the sort; the largest count into most.
@compute @workgroup_size(64)
fn sort_offsets_of(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = sort_invocation(gid);
    if (p > sort_params.pixels) {
        return;
    }
    let start = sort_lower_bound(p);
    sort_offsets[p] = start;
    if (p < sort_params.pixels) {
        atomicMax(&sort_most[0], sort_lower_bound(p + 1u) - start);
    }
}
