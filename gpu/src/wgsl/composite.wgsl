// The compositor's entry point (mlab_gpu::Compositor): one invocation per stored pixel, which
// inserts its fragments in submission order (sorted by pixel, stably: sort.wgsl on the GPU, or
// the CPU) and writes its slots. Bindings (group 0):
//   0 uniform          CompositeParams
//   1 storage, read    offsets: array<u32>, pixels + 1 entries; pixel p's fragments are
//                      positions offsets[p] .. offsets[p + 1] in pixel order
//   2 storage, read    fragments: array<u32>, COMPOSITE_WORDS words per fragment (the layout
//                      of mlab_gpu::GpuFragment: pixel, bits of premultiplied R, G, B, alpha,
//                      depth (f32), key, keyed), in submission order (or in pixel order:
//                      `sorted`)
//   3 storage, rw      rows: array<vec2<u32>>, the framebuffer's storage (Row::words)
//   4 storage, rw      image: array<u32>, RGBA8 pixels (entry point `resolve`)
//   5 storage, read    order: array<vec2<u32>>, the fragments sorted by pixel, stably: (stored
//                      pixel of the band, index into fragments); `composite` reads the index
struct CompositeParams {
    // Stored pixels in this dispatch (padding lanes of spans included).
    pixels: u32,
    // Invocations per row of the 2-D dispatch (workgroups in x times 64).
    pitch: u32,
    // 1: 8-pixel layer-major spans (mlab::Spans); 0: pixel-major (mlab::PixelMajor).
    spans: u32,
    // This dispatch inserts fragments first .. first + chunk of each pixel; 0 starts from empty
    // rows, later dispatches load the rows the previous one stored.
    first: u32,
    // Image width, and stored pixels per line (the width, or 8 * ceil(width / 8) for spans).
    width: u32,
    line: u32,
    // 1: the fragments are already in pixel order (mlab_gpu::Sort::Cpu), binding 5 is not read;
    // 0: fragment i in pixel order is fragments[order[i].y] (mlab_gpu::Sort::Gpu).
    sorted: u32,
    // Fragments per pixel per dispatch, by the method's size (mlab_gpu's `chunk`). Mesa's
    // llvmpipe (lavapipe) ends an invocation's loops after 65,535 iterations in all (gallivm's
    // loop limiter, one counter per shader function, inner loops counted unless the compiler
    // unrolled them, a guard against endless shaders): a pixel with more would silently lose the
    // rest. The chunk keeps every loop of an invocation within the limit even with no loop
    // unrolled; a pixel with more fragments is continued by further dispatches (`first`), which
    // load its rows back. This also bounds the run time of one invocation (GPU watchdogs).
    chunk: u32,
    // The background for `resolve`: three channels as mlab_gpu::background_q15 gives them, and
    // w = 1 (opaque) or 0 (Background::Transparent).
    background: vec4<u32>,
}

@group(0) @binding(0) var<uniform> composite_params: CompositeParams;
@group(0) @binding(1) var<storage, read> composite_offsets: array<u32>;
@group(0) @binding(2) var<storage, read> composite_fragments: array<u32>;
@group(0) @binding(3) var<storage, read_write> composite_rows: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read> composite_order: array<vec2<u32>>;
// Written only by the entry point `resolve` (composite_resolve.wgsl, composite_resolve_ht.wgsl).
@group(0) @binding(4) var<storage, read_write> composite_image: array<u32>;

// The stored pixel of invocation gid of the 2-D dispatch (`pitch` invocations per row).
fn composite_invocation(gid: vec3<u32>) -> u32 {
    return gid.y * composite_params.pitch + gid.x;
}

// The fragments stored pixel p inserts in this `composite` dispatch, as positions start .. end
// in pixel order (`composite_fragment_at`); start > end: nothing to do (past the dispatch's
// pixels, or an earlier dispatch inserted all of the pixel's fragments and its rows are final).
fn composite_range(p: u32) -> vec2<u32> {
    if (p >= composite_params.pixels) {
        return vec2<u32>(1u, 0u);
    }
    let start = composite_offsets[p] + composite_params.first;
    let end = min(composite_offsets[p + 1u], start + composite_params.chunk);
    if (composite_params.first != 0u && start >= end) {
        return vec2<u32>(1u, 0u);
    }
    return vec2<u32>(start, end);
}

// No image pixel (composite_image_index).
const COMPOSITE_NONE: u32 = 0xffffffffu;

// The image index of stored pixel p of a `resolve` dispatch, or COMPOSITE_NONE past the
// dispatch's pixels and on the padding lanes of spans.
fn composite_image_index(p: u32) -> u32 {
    if (p >= composite_params.pixels) {
        return COMPOSITE_NONE;
    }
    let x = p % composite_params.line;
    if (x >= composite_params.width) {
        return COMPOSITE_NONE;
    }
    return (p / composite_params.line) * composite_params.width + x;
}

// Index of slot j (of `slots` per pixel) of stored pixel p.
fn composite_slot(p: u32, j: u32, slots: u32) -> u32 {
    if (composite_params.spans != 0u) {
        return ((p >> 3u) * slots + j) * 8u + (p & 7u);
    }
    return p * slots + j;
}

// Words per fragment (mlab_gpu::GpuFragment).
const COMPOSITE_WORDS: u32 = 8u;

// A fragment quantized into its row, and its hash in its pixel.
struct composite_fragment {
    row: vec2<u32>,
    h: u32,
}

// The i-th fragment in pixel order: its hash h = mlab_fragment_hash(key, pixel), with its stable
// key when `keyed` is not 0 and its content key otherwise (mlab::Fragment::hash; the pixel id is
// the fragment's `pixel`, y * width + x, in every band), and its row quantized with h.
fn composite_fragment_at(i: u32) -> composite_fragment {
    var k = COMPOSITE_WORDS * i;
    if (composite_params.sorted == 0u) {
        k = COMPOSITE_WORDS * composite_order[i].y;
    }
    let c = vec3<u32>(composite_fragments[k + 1u], composite_fragments[k + 2u], composite_fragments[k + 3u]);
    let a = composite_fragments[k + 4u];
    let z = composite_fragments[k + 5u];
    let key = select(mlab_content_key(c, a, z), composite_fragments[k + 6u], composite_fragments[k + 7u] != 0u);
    let h = mlab_fragment_hash(key, composite_fragments[k]);
    return composite_fragment(mlab_quantize(c, a, z, h), h);
}

// Slot j (of `slots` per pixel) of stored pixel p as this `composite` dispatch starts: `empty`
// (MLAB_EMPTY_ROW, MLAB_EMPTY_TAIL) in the first dispatch, else what the previous one stored.
fn composite_load(p: u32, j: u32, slots: u32, empty: vec2<u32>) -> vec2<u32> {
    return select(composite_rows[composite_slot(p, j, slots)], empty, composite_params.first == 0u);
}

// The entry points. Each method's text (composite_mlab.wgsl, composite_ht.wgsl) defines
// composite_pixel(p, range), which loads stored pixel p's slots, inserts its fragments
// range.x .. range.y and stores the slots back; its resolve text (composite_resolve.wgsl,
// composite_resolve_ht.wgsl) defines composite_resolve_pixel(p), the RGBA8 pixel of its slots.

// Every stored pixel of the dispatch inserts its fragments of this dispatch (composite_range).
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = composite_invocation(gid);
    let range = composite_range(p);
    if (range.x > range.y) {
        return;
    }
    composite_pixel(p, range);
}

// The integer RGBA8 resolve of every image pixel of the dispatch (padding lanes skipped), after
// the `composite` dispatches: the bytes of the kernel's Framebuffer::resolve_rgba8.
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = composite_invocation(gid);
    let i = composite_image_index(p);
    if (i == COMPOSITE_NONE) {
        return;
    }
    composite_image[i] = composite_resolve_pixel(p);
}
