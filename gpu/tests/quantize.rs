//! The kernel's one f32 step, `floor(v * 255 + u)` (`docs/layout.md`): could a fused
//! multiply-add change a byte? And the shader's integer emulation of that step, checked on
//! the GPU against the CPU's f32 arithmetic.
//!
//! Notation: `v` is a color channel or alpha (an f32 in `[0, 1]`), `u` a dither: `0.5` (the
//! paper's rounding and every non-faint fragment) or `(h + 0.5) / 256` for `h` in `0..=255`
//! (faint fragments of `Unbiased`; `h` is the top byte of the fragment's hash), so
//! `u = U / 512` with `U` odd in `1..=511`, or `U = 256`. The kernel computes `fl(fl(v * 255) + u)` and truncates; a contracted FMA computes
//! `fl(v * 255 + u)` (one rounding).
//!
//! Which pairs can differ: let `p = v * 255` exactly (at most 32 significant bits: exact in
//! f64). Below 256 an f32 ulp is at most 2^-16, so `|fl(p) - p| <= 2^-17` and
//! `|fl(fl(p) + u) - (p + u)| <= 2^-17 + 2^-16 < 2^-14`, and `|fl(p + u) - (p + u)| <= 2^-16`.
//! Rounding is monotone and integers are f32 values, so both truncate to `floor(p + u)`
//! unless `p + u` lies within `2^-14` of an integer `k` (only `k = floor(p) + 1` is possible:
//! `0 < u < 1`). For each `v` that window holds at most one `U` (the `U` are `1/512` apart and
//! the window is `2^-13` wide). `critical_pairs` lists, for every f32 in `[0, 1]`, the `U` in
//! its window: both arithmetics are compared on those, and, as a check of the argument, on
//! every `U` for a sample of `v`.

mod common;

use std::sync::OnceLock;

use mlab_gpu::wgsl;

/// Every dither numerator: `u = U / 512`.
fn numerators() -> impl Iterator<Item = u32> {
    (0..256).map(|h| 2 * h + 1).chain([256])
}

fn dither(numerator: u32) -> f32 {
    if numerator == 256 {
        0.5
    } else {
        // The kernel's expression for h = (U - 1) / 2.
        (((numerator - 1) / 2) as f32 + 0.5) * (1.0 / 256.0)
    }
}

/// The kernel's step (`quantize`, `quantize_with_dither`: multiply, then add, then truncate).
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "the kernel's cast"
)]
fn separate(v: f32, u: f32) -> u8 {
    (v * 255.0 + u) as u8
}

/// The same with one rounding.
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "the kernel's cast"
)]
fn fused(v: f32, u: f32) -> u8 {
    v.mul_add(255.0, u) as u8
}

/// The numerator whose `p + u` lies within 2^-14 of an integer, if any.
fn window(v: f32) -> Option<u32> {
    let p = f64::from(v) * 255.0;
    let t = (p.floor() + 1.0 - p) * 512.0;
    let n = t.round();
    #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "n in 0..=512")]
    let n32 = n as u32;
    ((t - n).abs() <= 1.0 / 32.0 && (n32 % 2 == 1 || n32 == 256) && n32 < 512).then_some(n32)
}

/// `(v bits, numerator)` for every f32 `v` in `[0, 1]` and its numerator in the window.
fn critical_pairs() -> &'static [(u32, u32)] {
    static PAIRS: OnceLock<Vec<(u32, u32)>> = OnceLock::new();
    PAIRS.get_or_init(|| {
        let end = 1.0f32.to_bits() + 1;
        let half = end / 2;
        std::thread::scope(|s| {
            let scan = |a: u32, b: u32| {
                move || {
                    (a..b)
                        .filter_map(|bits| window(f32::from_bits(bits)).map(|n| (bits, n)))
                        .collect::<Vec<_>>()
                }
            };
            let first = s.spawn(scan(0, half));
            let mut pairs = scan(half, end)();
            let mut all = first.join().expect("scan thread");
            all.append(&mut pairs);
            all
        })
    })
}

#[test]
fn a_fused_multiply_add_changes_bytes_of_faint_fragments_only() {
    let pairs = critical_pairs();
    let mut differ = Vec::new();
    for &(bits, n) in pairs {
        let v = f32::from_bits(bits);
        let u = dither(n);
        if separate(v, u) != fused(v, u) {
            differ.push((v, u, separate(v, u), fused(v, u)));
        }
    }
    println!(
        "{} f32 in [0, 1]; {} pairs within 2^-14 of an integer; {} differ with an FMA:",
        1.0f32.to_bits() + 1,
        pairs.len(),
        differ.len()
    );
    for (v, u, s, f) in &differ {
        println!(
            "  v = {v:e} ({:#010x}), u = {u} (h = {}): separate {s}, fused {f}",
            v.to_bits(),
            (u * 256.0) as u32
        );
    }
    // The finding: a contracted FMA does change bytes, so the shader must not use f32.
    assert!(
        !differ.is_empty(),
        "no byte changes: the shader could use f32 arithmetic"
    );
    for &(v, u, s, f) in &differ {
        // Never with u = 0.5 (the paper's rounding, every fragment that is not faint) ...
        assert_ne!(u, 0.5);
        // ... only where fl(v * 255) + u rounds up to exactly 1 (v * 255 below 1/2).
        assert_eq!((s, f), (1, 0), "{v:e} {u}");
        assert!(v * 255.0 < 0.5);
    }
}

/// The integer resolve's background step `floor(b * 32640 + 0.5)` (`docs/layout.md`,
/// `mlab_gpu::background_q15`), separately rounded and fused.
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "the kernel's cast"
)]
fn background_differs(b: f32) -> bool {
    (b * 32640.0 + 0.5) as u32 != b.mul_add(32640.0, 0.5) as u32
}

#[test]
fn the_resolves_background_step_is_the_same_with_an_fma_for_every_f32_in_0_1() {
    let end = 1.0f32.to_bits() + 1;
    let count = |a: u32, b: u32| (a..b).filter(|&bits| background_differs(f32::from_bits(bits))).count();
    let differ = std::thread::scope(|s| {
        let first = s.spawn(|| count(0, end / 2));
        count(end / 2, end) + first.join().expect("scan thread")
    });
    assert_eq!(differ, 0, "an FMA changes the background's Q15 value");
}

#[test]
fn outside_the_window_every_dither_gives_the_same_byte_with_and_without_fma() {
    // A check of the argument above: every numerator, for every 997th f32 in [0, 1] and for
    // every f32 of the critical ranges (v * 255 just below 1 / 512 .. 1 / 2).
    let sample = (0..=1.0f32.to_bits()).step_by(997).chain(0x3800_0000..0x3800_4000);
    for bits in sample {
        let v = f32::from_bits(bits);
        let w = window(v);
        for n in numerators() {
            let u = dither(n);
            if Some(n) != w {
                let exact = (f64::from(v) * 255.0 + f64::from(n) / 512.0).floor();
                assert_eq!(f64::from(separate(v, u)), exact, "{v:e} {n}");
                assert_eq!(f64::from(fused(v, u)), exact, "{v:e} {n}");
            }
        }
    }
}

/// Runs `entry` of `KERNEL` + the test entry points over `input` (two words per item for
/// `pairs`, one for `mul255`), returns one word per item.
fn run(gpu: &mlab_gpu::Gpu, entry: &str, input: &[u32], items: u32) -> Vec<u32> {
    run_with(gpu, entry, input, items, 0, 1)
}

/// [`run`] with `base` in the uniform's third word and `words` output words per item.
fn run_with(gpu: &mlab_gpu::Gpu, entry: &str, input: &[u32], items: u32, base: u32, words: u32) -> Vec<u32> {
    const ENTRIES: &str = r"
@group(0) @binding(0) var<storage, read> test_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> test_out: array<u32>;
@group(0) @binding(2) var<uniform> test_n: vec4<u32>;
fn test_index(gid: vec3<u32>) -> u32 { return gid.y * test_n.y + gid.x; }
@compute @workgroup_size(64) fn quantize(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = test_index(gid);
    if (i < test_n.x) { test_out[i] = mlab_quantize_byte(test_in[2u * i], test_in[2u * i + 1u]); }
}
@compute @workgroup_size(64) fn mul255(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = test_index(gid);
    if (i < test_n.x) { test_out[i] = mlab_f32_mul255(test_in[i]); }
}
@compute @workgroup_size(64) fn every(@builtin(global_invocation_id) gid: vec3<u32>) {
    // v = test_n.z + i: its product by 255 and its byte with u = 0.5 (the paper's rounding).
    _ = &test_in; // the layout of every entry point has the input binding
    let i = test_index(gid);
    if (i < test_n.x) {
        let v = test_n.z + i;
        test_out[2u * i] = mlab_f32_mul255(v);
        test_out[2u * i + 1u] = mlab_quantize_byte(v, 0x3f000000u);
    }
}
@compute @workgroup_size(64) fn add(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = test_index(gid);
    if (i < test_n.x) { test_out[i] = mlab_f32_add(test_in[2u * i], test_in[2u * i + 1u]); }
}
";
    let pipeline = common::pipeline(gpu, format!("{}{ENTRIES}", wgsl::KERNEL), entry);
    let ((gx, gy), pitch) = common::grid(items);
    let input = common::buffer(gpu, input, wgpu::BufferUsages::STORAGE);
    let n = common::buffer(gpu, &[items, pitch, base, 0], wgpu::BufferUsages::UNIFORM);
    let size = u64::from(items) * u64::from(words) * 4;
    common::dispatch_words(gpu, &pipeline, &[&input], &n, (gx, gy), size)
}

fn compare(what: &str, got: &[u32], want: &[u32], input: impl Fn(usize) -> String) {
    assert_eq!(got.len(), want.len());
    let bad: Vec<usize> = (0..got.len()).filter(|&i| got[i] != want[i]).take(5).collect();
    for &i in &bad {
        println!("{what}: {}: gpu {:#x}, cpu {:#x}", input(i), got[i], want[i]);
    }
    assert!(bad.is_empty(), "{what}: the shader differs from the CPU");
    println!("{what}: {} cases identical", got.len());
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_shader_quantizes_exactly_as_the_kernel_on_the_critical_pairs_and_a_sample_of_all() {
    let Some(gpu) = common::gpu("quantize") else { return };
    // Every critical pair, both signs of zero, and every dither for a sample of v.
    let mut pairs: Vec<(u32, u32)> = critical_pairs().to_vec();
    pairs.extend(
        (0..=1.0f32.to_bits())
            .step_by(65_537)
            .chain([0x8000_0000])
            .flat_map(|b| numerators().map(move |n| (b, n))),
    );
    let input: Vec<u32> = pairs.iter().flat_map(|&(v, n)| [v, dither(n).to_bits()]).collect();
    let want: Vec<u32> = pairs
        .iter()
        .map(|&(v, n)| u32::from(separate(f32::from_bits(v), dither(n))))
        .collect();
    let got = run(&gpu, "quantize", &input, pairs.len() as u32);
    compare("quantize", &got, &want, |i| {
        format!("v {:#x} U {}", pairs[i].0, pairs[i].1)
    });
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_shader_multiplies_by_255_and_adds_as_the_cpu_rounds() {
    let Some(gpu) = common::gpu("f32 emulation") else {
        return;
    };
    // v * 255 for every 61st f32 in [0, 1] and every subnormal of a range, then v + w for
    // pairs of non-negative f32 of every magnitude (subnormal, tiny, large, equal exponents).
    let vs: Vec<u32> = (0..=1.0f32.to_bits()).step_by(61).chain(0..0x1_0000).collect();
    let want: Vec<u32> = vs.iter().map(|&v| (f32::from_bits(v) * 255.0).to_bits()).collect();
    let got = run(&gpu, "mul255", &vs, vs.len() as u32);
    compare("mul255", &got, &want, |i| format!("v {:#x}", vs[i]));
    let mut rng = common::Rng(11);
    let mut pairs = Vec::new();
    while pairs.len() < 4_000_000 {
        let a = (rng.next() as u32) & 0x7fff_ffff;
        let b = match rng.below(3) {
            0 => (rng.next() as u32) & 0x7fff_ffff,
            1 => (a & 0xff80_0000) | (rng.next() as u32 & 0x007f_ffff), // same exponent
            _ => a.saturating_sub(rng.below(30 << 23)),                 // exponents close
        };
        let s = f32::from_bits(a) + f32::from_bits(b);
        if f32::from_bits(a).is_finite() && f32::from_bits(b).is_finite() && s.is_finite() {
            pairs.push([a, b]);
        }
    }
    let input: Vec<u32> = pairs.iter().flatten().copied().collect();
    let want: Vec<u32> = pairs
        .iter()
        .map(|&[a, b]| (f32::from_bits(a) + f32::from_bits(b)).to_bits())
        .collect();
    let got = run(&gpu, "add", &input, pairs.len() as u32);
    compare("add", &got, &want, |i| {
        format!("{:#x} + {:#x}", pairs[i][0], pairs[i][1])
    });
}

/// Every f32 in `[0, 1]` through the shader's `v * 255` and `floor(v * 255 + 0.5)`, in chunks
/// of 2^23 (about a minute on lavapipe with 2 cores; not in CI):
/// `cargo test -p mlab-gpu --test quantize -- --ignored`.
#[test]
#[ignore = "1.07e9 invocations: run on demand"]
fn every_f32_in_0_1_multiplies_and_rounds_as_the_cpu() {
    let Some(gpu) = common::gpu("every f32") else { return };
    let end = 1.0f32.to_bits() + 1;
    let chunk = 1u32 << 23;
    let placeholder = [0u32; 1];
    let mut base = 0;
    while base < end {
        let items = chunk.min(end - base);
        let got = run_with(&gpu, "every", &placeholder, items, base, 2);
        for i in 0..items {
            let v = f32::from_bits(base + i);
            let (m, q) = (got[2 * i as usize], got[2 * i as usize + 1]);
            assert_eq!(m, (v * 255.0).to_bits(), "v * 255, v = {v:e}");
            assert_eq!(q, u32::from(separate(v, 0.5)), "byte, v = {v:e}");
        }
        base += items;
    }
    println!("every f32 in [0, 1]: {end} products and bytes identical");
}
