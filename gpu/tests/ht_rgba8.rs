//! HT's RGBA8 on the GPU against the kernel, byte for byte: the WGSL integer resolve of HT
//! (`wgsl::HT_RESOLVE`, `docs/layout.md`, "Integer resolve of HT") and the compositor's
//! `composite_rgba8` for every K the kernel's run-time framebuffer offers, both arithmetics (both
//! tails), opaque and transparent backgrounds.
//!
//! 1. `ht_tail_resolve` alone: `(T, g)` on a grid of (alpha sum, count) pairs against the
//!    reference's independent formula (`mlab_reference::resolve_int::ht_tail`; the kernel's
//!    scalar `resolve::int::tail` is crate-private, its bytes are checked by 2).
//! 2. `ht_resolve_rgba8` on storage written directly (heads of any bytes, tails from fields on a
//!    grid, saturated and arbitrary tails) against `DynFramebuffer::resolve_rgba8`.
//! 3. The compositor's `composite_rgba8` on random and adversarial fragment streams against
//!    `mlab_gpu::cpu::resolve_rgba8` (the kernel's `DynFramebuffer` on the same fragments).

mod common;

use common::{Rng, buffer, gpu, grid, pipeline, saturating};
use mlab::glam::Vec3;
use mlab::hybrid::PaperTail;
use mlab::{ArithKind, Background, DynFramebuffer, Framebuffer, Layers, Paper, Row, Tail, TailFormat, Unbiased};
use mlab_gpu::{Compositor, Gpu, GpuFragment, Layout, background_q15, cpu, wgsl};

/// Backgrounds: transparent (premultiplied output), channels that are not byte values, the
/// extremes, and what the kernel clamps (NaN, negative, above 1, infinity, subnormal).
fn backgrounds() -> [Background; 6] {
    [
        Background::Transparent,
        Background::Opaque(Vec3::new(0.2, 0.5, 1.0)),
        Background::Opaque(Vec3::new(0.0, 0.0, 0.0)),
        Background::Opaque(Vec3::new(1.0, 1.0, 1.0)),
        Background::Opaque(Vec3::new(0.9, 0.9, 0.85)),
        Background::Opaque(Vec3::new(f32::NAN, -1.0, 2.0)),
    ]
}

fn storage(gpu: &Gpu, words: &[u32]) -> wgpu::Buffer {
    buffer(gpu, words, wgpu::BufferUsages::STORAGE)
}

fn uniform(gpu: &Gpu, words: &[u32; 8]) -> wgpu::Buffer {
    buffer(gpu, words, wgpu::BufferUsages::UNIFORM)
}

const TAIL_SHADER: &str = r"
@group(0) @binding(0) var<storage, read> test_in: array<u32>;
@group(0) @binding(1) var<storage, read_write> test_out: array<u32>;
@group(0) @binding(2) var<uniform> test_n: array<vec4<u32>, 2>; // cases, pitch
@compute @workgroup_size(64) fn tail(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * test_n[0].y + gid.x;
    if (i >= test_n[0].x) { return; }
    let tg = ht_tail_resolve(test_in[2u * i], test_in[2u * i + 1u]);
    test_out[2u * i] = tg.x;
    test_out[2u * i + 1u] = tg.y;
}
";

/// The (alpha sum, count) pairs: every alpha sum of the default tail (0..=16383) with every
/// count 0..=66 (zero count, the route-B limit n >= 64, route A's u < 1/2 and u >= 12
/// switches); the paper tail's larger sums (every third up to 65535) with counts around the
/// powers of two and the limits; every count 0..=65535 with the sums that put the mean at
/// the routes' boundary m = 1/4 (and one unit either side), at 1 (all-opaque), at one unit per
/// fragment, and at the clamp of u (4095) and the field maxima.
fn tail_pairs() -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    for alpha in 0..=16383 {
        for count in 0..=66 {
            pairs.push((alpha, count));
        }
    }
    let counts = [
        0, 1, 2, 3, 4, 5, 7, 8, 15, 16, 31, 32, 63, 64, 65, 127, 128, 255, 256, 257, 1000, 2046, 2047, 2048, 65534,
        65535,
    ];
    for alpha in (16384..=65535).step_by(3).chain([65534, 65535]) {
        for &count in &counts {
            pairs.push((alpha, count));
        }
    }
    for count in 0..=65535u32 {
        let quarter = (255 * count.max(1)) / 4;
        for alpha in [
            0,
            1,
            255,
            count,
            quarter.saturating_sub(1),
            quarter,
            quarter + 1,
            255 * count,
            4095,
            16383,
            65535,
        ] {
            pairs.push((alpha.min(65535), count));
        }
    }
    pairs
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_wgsl_tail_gives_the_references_t_and_g_on_a_grid_of_alpha_sums_and_counts() {
    let Some(gpu) = gpu("ht_tail") else { return };
    let pairs = tail_pairs();
    let items = u32::try_from(pairs.len()).expect("fits");
    let input: Vec<u32> = pairs.iter().flat_map(|&(a, n)| [a, n]).collect();
    let ((gx, gy), pitch) = grid(items);
    let pipe = pipeline(
        &gpu,
        format!("{}{TAIL_SHADER}", wgsl::hybrid(1, ArithKind::Unbiased).expect("text")),
        "tail",
    );
    let got = common::dispatch_words(
        &gpu,
        &pipe,
        &[&storage(&gpu, &input)],
        &uniform(&gpu, &[items, pitch, 0, 0, 0, 0, 0, 0]),
        (gx, gy),
        u64::from(items) * 8,
    );
    // Which branches the grid reaches (so that the test cannot pass on one route alone).
    let (mut route_a, mut series_g, mut zero, mut route_b) = (0, 0, 0, 0);
    let mut bad = Vec::new();
    for (i, &(alpha, count)) in pairs.iter().enumerate() {
        let (t, g) = mlab_reference::resolve_int::ht_tail(u64::from(alpha), u64::from(count));
        let want = [t as u32, g as u32];
        if got[2 * i..2 * i + 2] != want {
            bad.push((alpha, count, [got[2 * i], got[2 * i + 1]], want));
        }
        let m = 257 * alpha / count.max(1);
        if m <= 16384 {
            route_a += 1;
            if t == 0 {
                zero += 1;
            }
            if alpha > 0 && g != (65536 - t) * 255 / u64::from(alpha) {
                series_g += 1;
            }
        } else {
            route_b += 1;
        }
    }
    for (alpha, count, gpu, cpu) in bad.iter().take(8) {
        println!("S_a = {alpha}, n = {count}: gpu (T, g) = {gpu:?}, reference {cpu:?}");
    }
    assert!(bad.is_empty(), "{} of {items} tails differ", bad.len());
    assert!(route_a > 100_000 && route_b > 100_000 && zero > 1000 && series_g > 10_000);
    println!(
        "ht_tail_resolve: {items} (S_a, n) pairs identical (route A {route_a}, of which T = 0 {zero}, \
         g = h phi {series_g}; route B {route_b})"
    );
}

const RESOLVE_SHADER: &str = r"
@group(0) @binding(0) var<storage, read> test_rows: array<vec2<u32>>;
@group(0) @binding(1) var<storage, read_write> test_out: array<u32>;
@group(0) @binding(2) var<uniform> test_n: array<vec4<u32>, 2>; // (pixels, pitch), background
@compute @workgroup_size(64) fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * test_n[0].y + gid.x;
    if (p >= test_n[0].x) { return; }
    // Spans of 8 pixels (a width that is a multiple of 8): slot j of pixel p.
    let base = (p >> 3u) * (HT_K + 1u) * 8u + (p & 7u);
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = test_rows[base + 8u * j];
    }
    test_out[p] = ht_resolve_rgba8(&head, test_rows[base + 8u * HT_K], test_n[1]);
}
";

/// A head row: empty, opaque, a valid row (color at most its coverage), or any 8 bytes.
fn head_row(rng: &mut Rng) -> Row {
    let mut byte = || rng.below(256) as u8;
    let (r, g, b, t) = (byte(), byte(), byte(), byte());
    match rng.below(4) {
        0 => Row::EMPTY,
        1 => Row::new([r, g, b], 0, 1.0),
        2 => {
            let cap = 255 - u32::from(t);
            let c = |v: u8| (u32::from(v) * cap / 255) as u8;
            Row::new([c(r), c(g), c(b)], t, 2.0)
        }
        _ => Row::from_bytes(rng.next().to_le_bytes()),
    }
}

/// A tail's bytes: fields from the (alpha, count) lists (colors at most the alpha sum, at the
/// field maximum, or any), or any 8 bytes.
fn tail_bytes<T: TailFormat>(rng: &mut Rng, i: u32) -> [u8; 8] {
    let alphas = [0, 1, 64, 255, 1020, 4095, 4096, 8000, 16383, 20000, 65535];
    let counts = [0, 1, 2, 3, 4, 5, 16, 63, 64, 65, 255, 2047, 65535];
    let alpha = match rng.below(3) {
        0 => alphas[rng.below(alphas.len() as u32) as usize],
        1 => rng.below(T::ALPHA_MAX + 1),
        _ => rng.below(256) * (1 + rng.below(8)),
    };
    let count = match rng.below(3) {
        0 => counts[rng.below(counts.len() as u32) as usize],
        1 => rng.below(T::COUNT_MAX + 1),
        // All-opaque (alpha = 255 n) or one unit per fragment.
        _ => [alpha / 255, alpha, alpha / 64][rng.below(3) as usize],
    };
    let mut color = || match rng.below(4) {
        0 => rng.below(alpha.min(T::COLOR_MAX) + 1),
        1 => T::COLOR_MAX,
        2 => 0,
        _ => rng.below(T::COLOR_MAX + 1),
    };
    let sums = [color(), color(), color()];
    if i.is_multiple_of(16) {
        return rng.next().to_le_bytes();
    }
    T::from_sums(sums, alpha, count).to_bytes()
}

fn resolve_fields_in<T: TailFormat>(gpu: &Gpu, k: usize, arith: ArithKind, rng: &mut Rng) -> usize {
    let (w, h) = (64u32, 32u32);
    let layers = Layers::Hybrid(k);
    let mut rows = vec![Row::EMPTY; layers.rows_needed(w, h).expect("size")];
    // Spans: slot j of span s at (s * (K + 1) + j) * 8 + lane.
    for (s, span) in rows.chunks_exact_mut(8 * (k + 1)).enumerate() {
        for lane in 0..8 {
            for j in 0..k {
                span[8 * j + lane] = head_row(rng);
            }
            span[8 * k + lane] = Row::from_bytes(tail_bytes::<T>(rng, (8 * s + lane) as u32));
        }
    }
    let words: Vec<u32> = rows.iter().flat_map(|r| r.words()).collect();
    let pixels = w * h;
    let ((gx, gy), pitch) = grid(pixels);
    let pipe = pipeline(
        gpu,
        format!("{}{RESOLVE_SHADER}", wgsl::hybrid(k, arith).expect("text")),
        "resolve",
    );
    let input = storage(gpu, &words);
    for bg in backgrounds() {
        let q = background_q15(bg);
        let n = uniform(gpu, &[pixels, pitch, 0, 0, q[0], q[1], q[2], q[3]]);
        let got = common::dispatch_words(gpu, &pipe, &[&input], &n, (gx, gy), u64::from(pixels) * 4);
        let mut want = vec![[0u8; 4]; pixels as usize];
        let mut copy = rows.clone();
        match arith {
            ArithKind::Paper => {
                DynFramebuffer::<Paper>::new(layers, &mut copy, w, h).and_then(|fb| fb.resolve_rgba8(&mut want, bg))
            }
            ArithKind::Unbiased => {
                DynFramebuffer::<Unbiased>::new(layers, &mut copy, w, h).and_then(|fb| fb.resolve_rgba8(&mut want, bg))
            }
        }
        .expect("cpu resolve");
        if let Some(p) = (0..pixels as usize).find(|&p| got[p].to_le_bytes() != want[p]) {
            let s = (p / 8) * 8 * (k + 1) + p % 8;
            panic!(
                "K = {k} {arith:?} {bg:?}: pixel {p}: gpu {:?}, kernel {:?}; head {:?}, tail {:?}",
                got[p].to_le_bytes(),
                want[p],
                (0..k).map(|j| rows[s + 8 * j].to_bytes()).collect::<Vec<_>>(),
                T::from_bytes(rows[s + 8 * k].to_bytes()),
            );
        }
    }
    pixels as usize * backgrounds().len()
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_wgsl_ht_resolve_of_any_head_and_tail_bytes_is_the_kernels() {
    let Some(gpu) = gpu("ht_resolve_fields") else { return };
    let mut rng = Rng(0x6874_7267_6261_3821);
    let mut total = 0;
    for k in Layers::SIZES {
        total += resolve_fields_in::<PaperTail>(&gpu, k, ArithKind::Paper, &mut rng);
        total += resolve_fields_in::<Tail>(&gpu, k, ArithKind::Unbiased, &mut rng);
    }
    println!("ht_resolve_rgba8: {total} pixels (K = 1..=8, both tails, 6 backgrounds) identical");
}

/// GPU and CPU images of one stream; panics with the first differing pixel.
fn check_rgba8(
    c: &Compositor,
    layout: Layout,
    k: usize,
    arith: ArithKind,
    (w, h): (u32, u32),
    frags: &[GpuFragment],
    bg: Background,
) {
    let (words, image) = c.composite_rgba8(w, h, frags, bg).expect("gpu");
    let want = cpu::resolve_rgba8(Layers::Hybrid(k), arith, w, h, frags, bg).expect("cpu");
    assert_eq!(image.len(), want.len());
    if let Some(i) = (0..image.len()).find(|&i| image[i] != want[i]) {
        panic!(
            "K = {k} {arith:?} {w}x{h}, {} fragments, {bg:?}: pixel {i}: gpu {:?}, cpu {:?}",
            frags.len(),
            image[i],
            want[i]
        );
    }
    let rows = cpu::composite(Layers::Hybrid(k), arith, layout, w, h, frags).expect("cpu rows");
    assert_eq!(words, rows, "K = {k} {arith:?} {layout:?}: rows");
}

/// Faint, opaque, coplanar, additive and saturating streams into `n` pixels.
fn adversarial(rng: &mut Rng, n: u32) -> Vec<Vec<GpuFragment>> {
    let mut streams: Vec<Vec<GpuFragment>> = Vec::new();
    // Faint fragments (alpha 1/255 and the dithers' range), distinct depths: long tails of
    // small alpha sums (route A, u < 1/2: g = h phi).
    streams.push(
        (0..4000)
            .map(|i| {
                GpuFragment::new(
                    i % n,
                    [
                        0.5 / 255.0,
                        1.0 / 255.0,
                        0.0,
                        [1.0 / 255.0, 15.9 / 255.0, 3.0 / 255.0][(i % 3) as usize],
                    ],
                    (i / n) as f32 * 0.25,
                )
            })
            .collect(),
    );
    // Opaque fragments in random order, and coplanar ones: all-opaque tails (S_a = 255 n).
    streams.extend(rng.opaque_and_coplanar(n, 3000));
    // Additive light only (alpha 0: tails with S_a = 0 and a count) and invisible fragments.
    streams.push(rng.edited(n, 3000, |i, f| {
        f.rgba[3] = 0.0;
        if i % 3 == 0 {
            f.rgba = [0.0; 4];
        }
    }));
    // Saturating tails: bright fragments, half opaque, into 3 pixels (colors, alpha and the
    // default tail's count saturate).
    streams.push(saturating(7000));
    // Mid alphas around the routes' boundary (mean alpha near 1/4) with random depths.
    streams.push(rng.edited(n, 4000, |i, f| {
        f.rgba[3] = [0.25, 64.0 / 255.0, 63.0 / 255.0, 0.5][i % 4];
        f.rgba[0] = f.rgba[0].min(f.rgba[3]);
    }));
    streams
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn ht_rgba8_from_the_compositor_is_the_kernels_for_every_k_and_arithmetic() {
    let Some(gpu) = gpu("ht_rgba8") else { return };
    let mut rng = Rng(0x4854_5247_4241);
    let bgs = backgrounds();
    let mut total = 0;
    let mut config = 0usize;
    for k in Layers::SIZES {
        for arith in ArithKind::ALL {
            let layout = if config.is_multiple_of(3) {
                Layout::PixelMajor
            } else {
                Layout::Spans
            };
            config += 1;
            let c = Compositor::new(&gpu, Layers::Hybrid(k), arith, layout).expect("compositor");
            let mut streams: Vec<(u32, u32, Vec<GpuFragment>)> = [(37u32, 11u32, 5000usize), (8, 2, 800), (1, 1, 60)]
                .into_iter()
                .map(|(w, h, n)| (w, h, (0..n).map(|_| rng.fragment_in(w * h)).collect()))
                .collect();
            streams.extend(adversarial(&mut rng, 13 * 3).into_iter().map(|s| (13, 3, s)));
            // The random streams again with stable keys on most fragments (HT's head and tail
            // take no hash: the keys reach the bytes through the faint fragments' dither).
            for s in 0..3 {
                let (w, h, frags) = streams[s].clone();
                streams.push((w, h, rng.keyed(frags)));
            }
            for (i, (w, h, frags)) in streams.iter().enumerate() {
                // Transparent, and one opaque background in turn.
                for bg in [bgs[0], bgs[1 + (config + i) % (bgs.len() - 1)]] {
                    check_rgba8(&c, layout, k, arith, (*w, *h), frags, bg);
                    total += frags.len();
                }
            }
        }
    }
    println!("HT rgba8: {total} fragments through the GPU and the CPU, identical images and rows");
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn ht_rgba8_at_the_tails_count_limits_is_the_kernels() {
    let Some(gpu) = gpu("ht_rgba8_limits") else { return };
    // Pixel i receives K + limit - 2 + i fragments that all reach the tail (additive light:
    // alpha 0 except every fifth, distinct colors, never invisible): counts limit - 2 ..=
    // limit + 1, the last two saturated. Tail: limit 2047; PaperTail: 65535 (three dispatches).
    for (arith, limit) in [(ArithKind::Unbiased, 2047u32), (ArithKind::Paper, 65535)] {
        for k in [1usize, 8] {
            let mut frags = Vec::new();
            for p in 0..4u32 {
                let n = k as u32 + limit - 2 + p;
                frags.extend((0..n).map(|i| {
                    GpuFragment::new(
                        p,
                        [
                            (i % 7) as f32 / 1785.0 + 1.0 / 255.0,
                            0.0,
                            0.002,
                            if i % 5 == 0 { 0.003 } else { 0.0 },
                        ],
                        i as f32,
                    )
                }));
            }
            let c = Compositor::new(&gpu, Layers::Hybrid(k), arith, Layout::PixelMajor).expect("compositor");
            for bg in [Background::Transparent, Background::Opaque(Vec3::new(0.2, 0.5, 1.0))] {
                check_rgba8(&c, Layout::PixelMajor, k, arith, (4, 1), &frags, bg);
            }
            // The counts are where the test says: the last two pixels' tails saturated.
            let words = c.composite(4, 1, &frags).expect("gpu");
            let count = |p: usize| {
                let t = 2 * (p * (k + 1) + k);
                let bytes: [u8; 8] = bytemuck::cast([words[t], words[t + 1]]);
                match arith {
                    ArithKind::Paper => PaperTail::from_bytes(bytes).count(),
                    ArithKind::Unbiased => Tail::from_bytes(bytes).count(),
                }
            };
            assert_eq!(
                [count(0), count(1), count(2), count(3)],
                [limit - 2, limit - 1, limit, limit],
                "K = {k} {arith:?}"
            );
        }
    }
}
