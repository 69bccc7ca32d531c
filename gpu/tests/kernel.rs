//! The WGSL merges, tail adds, hashes and quantization against the kernel's, on every
//! combination of the bytes they read: each GPU invocation builds its operands from its index
//! with integer operations (the same expressions as `operands` below), applies one function of
//! `wgsl::KERNEL` and writes the result word; the CPU does the same with
//! `mlab::Arithmetic::merge`, `TailFormat::add`, `mlab::fragment_hash` and
//! `Arithmetic::quantize`.

mod common;

use mlab::glam::Vec3;
use mlab::mlab::row_hash;
use mlab::{Arithmetic, Fragment, Paper, Row, Tail, TailFormat, Unbiased, fragment_hash, hybrid::PaperTail};
use mlab_gpu::wgsl;

/// 2^24 cases: `i = a | b << 8 | t << 16` for every front color byte `a`, back color byte `b`
/// and front transmittance `t`; the other bytes, the depths and the merge's hash vary with a
/// hash of `i`.
const CASES: u32 = 1 << 24;

const SHADER: &str = r"
@group(0) @binding(0) var<storage, read_write> test_out: array<u32>;
@group(0) @binding(1) var<uniform> test_n: vec4<u32>; // cases, pitch, which
fn test_hash(i: u32) -> u32 {
    var x = i * 0x9e3779b9u;
    x ^= x >> 15u;
    x *= 0x85ebca6bu;
    x ^= x >> 13u;
    return x;
}
// The depths of the two rows: the front's any finite f32 (either sign); the back's, by a third
// hash: random finite, the front's plus a 16-bit or a 24-bit step of its bits (diff & 0xffff
// and diff >> 16 of the centroid's step), equal, of the other sign, the empty row's +infinity,
// any bits (NaN included), a signed zero.
fn test_depths(h: u32) -> vec2<u32> {
    let x = test_hash(h ^ 0x2545f491u);
    let y = test_hash(x);
    let zf = x & 0xff7fffffu;
    var zb = y & 0xff7fffffu;
    switch (test_hash(y) >> 29u) {
        case 1u: { zb = zf + (y & 0xffffu); }
        case 2u: { zb = zf + (y & 0xffffffu); }
        case 3u: { zb = zf; }
        case 4u: { zb = zf ^ 0x80000000u; }
        case 5u: { zb = 0x7f800000u; }
        case 6u: { zb = y; }
        case 7u: { zb = y & 0x80000000u; }
        default: {}
    }
    return vec2<u32>(zf, zb);
}
@compute @workgroup_size(64) fn run(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * test_n.y + gid.x;
    if (i >= test_n.x) { return; }
    let a = i & 0xffu;
    let b = (i >> 8u) & 0xffu;
    let t = (i >> 16u) & 0xffu;
    let h = test_hash(i);
    let z = test_depths(h);
    let front = vec2<u32>(a | (((h >> 8u) & 0xffu) << 8u) | ((255u - a) << 16u) | (t << 24u), z.x);
    let back = vec2<u32>(b | ((255u - b) << 8u) | (((h >> 16u) & 0xffu) << 16u) | (((h >> 24u) ^ a) << 24u), z.y);
    // The inserted fragment's hash, which seeds the merge's dither.
    let mh = test_hash(h + 5u);
    // A tail whose bits are 1 with probability 3/4 (fields often at or near saturation), and the
    // back row as the one that left the head.
    let tail = vec2<u32>(test_hash(h + 1u) | test_hash(h + 3u), test_hash(h + 2u) | test_hash(h + 4u));
    // A fragment: alpha any f32 in [0, 1], faint (below 16 / 255) half the time, color at most
    // alpha (non-negative f32 order as their bits), depth the front row's.
    let fa = select(test_hash(h + 6u) % 0x3f800001u, test_hash(h + 6u) % 0x3d808081u, (h & 1u) == 0u);
    let fc = vec3<u32>(test_hash(h + 7u) % (fa + 1u), test_hash(h + 8u) % (fa + 1u), test_hash(h + 9u) % (fa + 1u));
    var w = vec2<u32>(0u);
    switch test_n.z {
        case 0u: { w = mlab_merge_paper(front, back, mh); }
        case 1u: { w = mlab_merge_unbiased(front, back, mh); }
        case 2u: { w = mlab_tail_add_paper(tail, back); }
        case 3u: { w = mlab_tail_add_wide(tail, back); }
        case 4u: { w = vec2<u32>(mlab_fragment_hash(h, i), mlab_row_hash(front, i)); }
        case 5u: { w = mlab_quantize_paper(fc, fa, z.x, mh); }
        default: { w = mlab_quantize_unbiased(fc, fa, z.x, mh); }
    }
    test_out[2u * i] = w.x;
    test_out[2u * i + 1u] = w.y;
}
";

fn hash(i: u32) -> u32 {
    let mut x = i.wrapping_mul(0x9e37_79b9);
    x ^= x >> 15;
    x = x.wrapping_mul(0x85eb_ca6b);
    x ^= x >> 13;
    x
}

/// The depths of case hash `h`, as the shader's `test_depths`.
fn depths(h: u32) -> [u32; 2] {
    let x = hash(h ^ 0x2545_f491);
    let y = hash(x);
    let zf = x & 0xff7f_ffff;
    let zb = match hash(y) >> 29 {
        1 => zf.wrapping_add(y & 0xffff),
        2 => zf.wrapping_add(y & 0xff_ffff),
        3 => zf,
        4 => zf ^ 0x8000_0000,
        5 => 0x7f80_0000,
        6 => y,
        7 => y & 0x8000_0000,
        _ => y & 0xff7f_ffff,
    };
    [zf, zb]
}

/// The operands of case `i`, as the shader builds them.
struct Operands {
    front: Row,
    back: Row,
    /// The merge's (the inserted fragment's) hash.
    mh: u32,
    tail: [u32; 2],
    /// The fragment: bits of premultiplied R, G, B, alpha, depth.
    fragment: [u32; 5],
}

impl core::fmt::Debug for Operands {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "front {:08x?} back {:08x?} h {:#010x} tail {:08x?} fragment {:08x?}",
            self.front.words(),
            self.back.words(),
            self.mh,
            self.tail,
            self.fragment
        )
    }
}

fn operands(i: u32) -> Operands {
    let (a, b, t, h) = (i & 0xff, (i >> 8) & 0xff, (i >> 16) & 0xff, hash(i));
    let [zf, zb] = depths(h);
    let front = Row::from_words([a | ((h >> 8) & 0xff) << 8 | (255 - a) << 16 | t << 24, zf]);
    let back = Row::from_words([
        b | (255 - b) << 8 | ((h >> 16) & 0xff) << 16 | ((h >> 24) ^ a) << 24,
        zb,
    ]);
    let tail = [
        hash(h.wrapping_add(1)) | hash(h.wrapping_add(3)),
        hash(h.wrapping_add(2)) | hash(h.wrapping_add(4)),
    ];
    let fa = if h & 1 == 0 {
        hash(h.wrapping_add(6)) % 0x3d80_8081
    } else {
        hash(h.wrapping_add(6)) % 0x3f80_0001
    };
    let c = |k: u32| hash(h.wrapping_add(k)) % (fa + 1);
    Operands {
        front,
        back,
        mh: hash(h.wrapping_add(5)),
        tail,
        fragment: [c(7), c(8), c(9), fa, zf],
    }
}

fn expected(which: u32, i: u32) -> [u32; 2] {
    let Operands {
        front,
        back,
        mh,
        tail,
        fragment,
    } = operands(i);
    let bytes = |w: [u32; 2]| Row::from_words(w).to_bytes();
    let words = |b: [u8; 8]| Row::from_bytes(b).words();
    let f = || {
        let [r, g, b, a, z] = fragment.map(f32::from_bits);
        Fragment::premultiplied(Vec3::new(r, g, b), a, z).expect("a valid fragment")
    };
    match which {
        0 => Paper::merge(front, back, mh).words(),
        1 => Unbiased::merge(front, back, mh).words(),
        2 => {
            let mut t = PaperTail::from_bytes(bytes(tail));
            t.add(back);
            words(t.to_bytes())
        }
        3 => {
            let mut t = Tail::from_bytes(bytes(tail));
            t.add(back);
            words(t.to_bytes())
        }
        4 => [fragment_hash(hash(i), i), row_hash(front, i)],
        5 => Paper::quantize(&f(), mh).words(),
        _ => Unbiased::quantize(&f(), mh).words(),
    }
}

fn gpu_words(gpu: &mlab_gpu::Gpu, which: u32) -> Vec<u32> {
    let pipeline = common::pipeline(gpu, format!("{}{SHADER}", wgsl::KERNEL), "run");
    let ((gx, gy), pitch) = common::grid(CASES);
    let size = u64::from(CASES) * 8;
    let n = common::buffer(gpu, &[CASES, pitch, which, 0], wgpu::BufferUsages::UNIFORM);
    common::dispatch_words(gpu, &pipeline, &[], &n, (gx, gy), size)
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn merges_tail_adds_hashes_and_quantization_match_the_kernel_on_every_byte_combination() {
    let Some(gpu) = common::gpu("kernel functions") else {
        return;
    };
    for (which, name) in [
        (0, "merge paper"),
        (1, "merge unbiased"),
        (2, "tail add paper"),
        (3, "tail add wide"),
        (4, "fragment and row hashes"),
        (5, "quantize paper"),
        (6, "quantize unbiased"),
    ] {
        let got = gpu_words(&gpu, which);
        let at = |i: u32| [got[2 * i as usize], got[2 * i as usize + 1]];
        let bad: Vec<u32> = (0..CASES).filter(|&i| at(i) != expected(which, i)).take(5).collect();
        for &i in &bad {
            println!(
                "{name}: case {i:#x} {:?}: gpu {:08x?}, cpu {:08x?}",
                operands(i),
                at(i),
                expected(which, i)
            );
        }
        assert!(bad.is_empty(), "{name} differs");
        println!("{name}: {CASES} cases identical");
    }
}
