//! The WGSL merges and tail adds against the kernel's, on every combination of the bytes they
//! read: each GPU invocation builds its operands from its index with integer operations (the
//! same expressions as `operands` below), applies one function of `wgsl::KERNEL` and writes the
//! result word; the CPU does the same with `mlab::Arithmetic::merge` and `TailFormat::add`.

mod common;

use mlab::{Arithmetic, Paper, Row, Tail, TailFormat, Unbiased, hybrid::PaperTail};
use mlab_gpu::wgsl;
use wgpu::util::DeviceExt;

/// 2^24 cases: `i = a | b << 8 | t << 16` for every front color byte `a`, back color byte `b`
/// and front transmittance `t`; the other bytes and the depths vary with a hash of `i` (the
/// merge dither of `Unbiased` hashes all of them).
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
@compute @workgroup_size(64) fn run(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * test_n.y + gid.x;
    if (i >= test_n.x) { return; }
    let a = i & 0xffu;
    let b = (i >> 8u) & 0xffu;
    let t = (i >> 16u) & 0xffu;
    let h = test_hash(i);
    let front = vec2<u32>(a | (((h >> 8u) & 0xffu) << 8u) | ((255u - a) << 16u) | (t << 24u), h & 0x7f7fffffu);
    let back = vec2<u32>(b | ((255u - b) << 8u) | (((h >> 16u) & 0xffu) << 16u) | (((h >> 24u) ^ a) << 24u), test_hash(h) & 0x7f7fffffu);
    // A tail whose bits are 1 with probability 3/4 (fields often at or near saturation), and the
    // back row as the one that left the head.
    let tail = vec2<u32>(test_hash(h + 1u) | test_hash(h + 3u), test_hash(h + 2u) | test_hash(h + 4u));
    var w = 0u;
    switch test_n.z {
        case 0u: { w = mlab_merge_paper(front, back).x; }
        case 1u: { w = mlab_merge_unbiased(front, back).x; }
        case 2u: { let r = mlab_tail_add_paper(tail, back); w = r.x ^ (r.y * 0x01000193u); }
        default: { let r = mlab_tail_add_wide(tail, back); w = r.x ^ (r.y * 0x01000193u); }
    }
    test_out[i] = w;
}
";

fn hash(i: u32) -> u32 {
    let mut x = i.wrapping_mul(0x9e37_79b9);
    x ^= x >> 15;
    x = x.wrapping_mul(0x85eb_ca6b);
    x ^= x >> 13;
    x
}

/// The rows and tail of case `i`, as the shader builds them.
fn operands(i: u32) -> (Row, Row, [u32; 2]) {
    let (a, b, t, h) = (i & 0xff, (i >> 8) & 0xff, (i >> 16) & 0xff, hash(i));
    let front = Row::from_words([a | ((h >> 8) & 0xff) << 8 | (255 - a) << 16 | t << 24, h & 0x7f7f_ffff]);
    let back = Row::from_words([
        b | (255 - b) << 8 | ((h >> 16) & 0xff) << 16 | ((h >> 24) ^ a) << 24,
        hash(h) & 0x7f7f_ffff,
    ]);
    let tail = [
        hash(h.wrapping_add(1)) | hash(h.wrapping_add(3)),
        hash(h.wrapping_add(2)) | hash(h.wrapping_add(4)),
    ];
    (front, back, tail)
}

fn tail_word(words: [u32; 2]) -> u32 {
    words[0] ^ words[1].wrapping_mul(0x0100_0193)
}

fn expected(which: u32, i: u32) -> u32 {
    let (front, back, tail) = operands(i);
    let bytes = |w: [u32; 2]| Row::from_words(w).to_bytes();
    let words = |b: [u8; 8]| Row::from_bytes(b).words();
    match which {
        0 => Paper::merge(front, back, i).words()[0],
        1 => Unbiased::merge(front, back, i).words()[0],
        2 => {
            let mut t = PaperTail::from_bytes(bytes(tail));
            t.add(back);
            tail_word(words(t.to_bytes()))
        }
        _ => {
            let mut t = Tail::from_bytes(bytes(tail));
            t.add(back);
            tail_word(words(t.to_bytes()))
        }
    }
}

fn gpu_words(gpu: &mlab_gpu::Gpu, which: u32) -> Vec<u32> {
    let device = gpu.device();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(format!("{}{SHADER}", wgsl::KERNEL).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("run"),
        compilation_options: Default::default(),
        cache: None,
    });
    let groups = CASES / 64;
    let (gx, gy) = (65535u32.min(groups), groups.div_ceil(65535u32.min(groups)));
    let size = u64::from(CASES) * 4;
    let n = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&[CASES, gx * 64, which, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    common::dispatch_words(gpu, &pipeline, &[], &n, (gx, gy), size)
}

#[test]
fn merges_and_tail_adds_match_the_kernel_on_every_byte_combination() {
    let Some(gpu) = common::gpu("kernel functions") else {
        return;
    };
    for (which, name) in [
        (0, "merge paper"),
        (1, "merge unbiased"),
        (2, "tail add paper"),
        (3, "tail add wide"),
    ] {
        let got = gpu_words(&gpu, which);
        let bad: Vec<u32> = (0..CASES)
            .filter(|&i| got[i as usize] != expected(which, i))
            .take(5)
            .collect();
        for &i in &bad {
            println!(
                "{name}: case {i:#x} {:?}: gpu {:#x}, cpu {:#x}",
                operands(i),
                got[i as usize],
                expected(which, i)
            );
        }
        assert!(bad.is_empty(), "{name} differs");
        println!("{name}: {CASES} cases identical");
    }
}
