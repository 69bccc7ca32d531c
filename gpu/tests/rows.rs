//! The compositor's rows against the CPU kernel (`DynFramebuffer`), byte for byte: random and
//! adversarial streams, every method and size the kernel offers at run time, both arithmetics,
//! both layouts; band splits; typed errors.

mod common;

use common::{Rng, gpu, saturating};
use mlab::glam::Vec3;
use mlab::{ArithKind, Background, FragmentError, Layers};
use mlab_gpu::{Compositor, GpuError, GpuFragment, Layout, Sort, cpu, wgsl};

fn all_layers() -> impl Iterator<Item = Layers> {
    Layers::SIZES
        .into_iter()
        .map(Layers::Mlab)
        .chain(Layers::SIZES.into_iter().map(Layers::Hybrid))
}

/// GPU and CPU words for one stream; panics with the first differing slot.
fn check(c: &Compositor, layers: Layers, arith: ArithKind, layout: Layout, w: u32, h: u32, frags: &[GpuFragment]) {
    let gpu = c.composite(w, h, frags).expect("gpu composite");
    let cpu = cpu::composite(layers, arith, layout, w, h, frags).expect("cpu composite");
    assert_eq!(gpu.len(), cpu.len(), "{layers:?} {arith:?} {layout:?} {w}x{h}");
    if let Some(i) = (0..gpu.len()).find(|&i| gpu[i] != cpu[i]) {
        let s = i / 2;
        panic!(
            "{layers:?} {arith:?} {layout:?} {w}x{h}, {} fragments: slot {s} differs: gpu {:08x} {:08x}, cpu {:08x} {:08x}",
            frags.len(),
            gpu[2 * s],
            gpu[2 * s + 1],
            cpu[2 * s],
            cpu[2 * s + 1]
        );
    }
}

fn random_stream(rng: &mut Rng, w: u32, h: u32, n: usize) -> Vec<GpuFragment> {
    (0..n)
        .map(|_| {
            let p = rng.below(w * h);
            rng.fragment(p)
        })
        .collect()
}

/// The binding cap of the band tests: 16 KiB, which splits [`banded_stream`]'s frame into bands
/// of one line.
const BAND_BYTES: u64 = 16384;

/// The band tests' frame and stream: 30 x 40 pixels and 15,000 random fragments, most with
/// stable keys. About 12 KB of fragments per line (12.5 per pixel, 32 bytes each) and 1 KB of
/// rows: [`BAND_BYTES`] bindings split the frame into bands of one line.
fn banded_stream(rng: &mut Rng) -> (u32, u32, Vec<GpuFragment>) {
    let (w, h) = (30, 40);
    let frags = random_stream(rng, w, h, 15_000);
    (w, h, rng.keyed(frags))
}

/// `run` on the whole frame, then with bindings capped at [`BAND_BYTES`] (which `c` keeps): the
/// same result, which it returns.
fn same_in_bands<T: PartialEq + std::fmt::Debug>(c: &mut Compositor, run: impl Fn(&Compositor) -> T) -> T {
    let whole = run(c);
    c.set_max_binding_bytes(BAND_BYTES);
    assert_eq!(c.max_binding_bytes(), BAND_BYTES);
    assert_eq!(run(c), whole, "bands against one band");
    whole
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn random_streams_match_the_cpu_for_every_method_size_and_arithmetic() {
    let Some(gpu) = gpu("random_streams") else { return };
    let mut rng = Rng(0x6d6c_6162_6770_7531);
    let (mut total, mut keyed) = (0usize, 0usize);
    for layers in all_layers() {
        for arith in ArithKind::ALL {
            // Spans (the DynFramebuffer's storage) for every size, pixel-major for every other.
            let layout = if total.is_multiple_of(3) {
                Layout::PixelMajor
            } else {
                Layout::Spans
            };
            let c = Compositor::new(&gpu, layers, arith, layout).expect("compositor");
            // The first and third streams with stable keys on most fragments (and content keys
            // on the others), the second and fourth with content keys only.
            for (s, (w, h, n)) in [(37, 23, 24_000), (8, 1, 3_000), (1, 1, 600), (64, 20, 9_000)]
                .into_iter()
                .enumerate()
            {
                let mut frags = random_stream(&mut rng, w, h, n);
                if s % 2 == 0 {
                    frags = rng.keyed(frags);
                    keyed += frags.iter().filter(|f| f.key().is_some()).count();
                }
                check(&c, layers, arith, layout, w, h, &frags);
                total += n;
            }
        }
    }
    println!("random: {total} fragments ({keyed} with a stable key) through the GPU and the CPU, identical rows");
    assert!(total >= 1_000_000);
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn every_layout_and_arithmetic_on_the_same_stream() {
    let Some(gpu) = gpu("layouts") else { return };
    let mut rng = Rng(7);
    let frags = random_stream(&mut rng, 19, 5, 4_000);
    let keyed = rng.keyed(frags.clone());
    for layers in [Layers::Mlab(3), Layers::Hybrid(7)] {
        for arith in ArithKind::ALL {
            for layout in [Layout::PixelMajor, Layout::Spans] {
                let c = Compositor::new(&gpu, layers, arith, layout).expect("compositor");
                check(&c, layers, arith, layout, 19, 5, &frags);
                check(&c, layers, arith, layout, 19, 5, &keyed);
            }
        }
    }
}

/// Faint, opaque, coplanar, extreme and saturating streams.
fn adversarial(rng: &mut Rng, w: u32, h: u32) -> Vec<Vec<GpuFragment>> {
    let n = w * h;
    let mut streams = Vec::new();
    // Many faint fragments per pixel (the dithers), distinct depths.
    streams.push(
        (0..20_000)
            .map(|i| {
                GpuFragment::new(
                    i % n,
                    [0.5 / 255.0, 1.0 / 255.0, 0.0, 1.0 / 255.0],
                    (i / n) as f32 * 0.25,
                )
            })
            .collect(),
    );
    // Faint fragments at the quantization's critical values (where an FMA would change the
    // byte): tiny colors with every dither.
    streams.push(
        (0..20_000u32)
            .map(|i| {
                let v = f32::from_bits(0x37c0_c080 + (i % 64) * 0x0010_0000);
                GpuFragment::new(
                    i % n,
                    [v, v * 0.5, v * 2.0, 15.9 / 255.0],
                    f32::from_bits(0x3f80_0000 + i),
                )
            })
            .collect(),
    );
    // Opaque fragments in random order (a z-buffer), and coplanar opaque ones.
    streams.extend(rng.opaque_and_coplanar(n, 10_000));
    // Equal depths, -0 against +0, extremes of f32, subnormal depths.
    streams.push(rng.edited(n, 10_000, |i, f| {
        f.depth = [0.0, -0.0, 1e-45, -1e-45, f32::MAX, -f32::MAX, f32::MIN_POSITIVE, 3.0][i % 8];
    }));
    // Saturating tails: thousands of bright fragments into a few pixels.
    streams.push(saturating(30_000));
    // Additive light only (alpha 0) and invisible fragments (nothing at all).
    streams.push(rng.edited(n, 10_000, |i, f| {
        f.rgba[3] = 0.0;
        if i % 2 == 0 {
            f.rgba = [0.0, 0.0, 0.0, 0.0];
        }
    }));
    // Stable keys: a faint fog of layers, one key per layer (the same key in every pixel: the
    // pixel id alone varies the hash), and the critical values with one key per fragment.
    let fog = streams[0]
        .iter()
        .enumerate()
        .map(|(i, f)| f.with_key(i as u32 / n))
        .collect();
    streams.push(fog);
    let critical = streams[1].iter().map(|f| f.with_key(f.depth.to_bits())).collect();
    streams.push(critical);
    // Coplanar, opaque and mixed streams with mixed keys.
    for s in 2..5 {
        let keyed = rng.keyed(streams[s].clone());
        streams.push(keyed);
    }
    streams
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn adversarial_streams_match_the_cpu() {
    let Some(gpu) = gpu("adversarial") else { return };
    let mut rng = Rng(23);
    let (w, h) = (13, 3);
    let streams = adversarial(&mut rng, w, h);
    let mut total = 0;
    for layers in [1, 2, 3, 4, 6, 8]
        .map(Layers::Mlab)
        .into_iter()
        .chain([1, 3, 7].map(Layers::Hybrid))
    {
        for arith in ArithKind::ALL {
            let c = Compositor::new(&gpu, layers, arith, Layout::Spans).expect("compositor");
            for s in &streams {
                check(&c, layers, arith, Layout::Spans, w, h, s);
                total += s.len();
            }
        }
    }
    println!("adversarial: {total} fragments, identical rows");
}

/// The color bytes of the words (every first word of a slot).
fn colors(words: &[u32]) -> Vec<u32> {
    words.iter().step_by(2).copied().collect()
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn stable_keys_seed_unbiaseds_dithers_on_the_gpu_as_on_the_cpu_and_paper_ignores_them() {
    let Some(gpu) = gpu("keys") else { return };
    // A faint fog: 40 layers over every pixel of 13 x 3 (alpha 0.03: faint, dithered), each
    // layer one primitive (its key), then the same fog 0.001 further away (a camera move).
    let (w, h) = (13, 3);
    let n = w * h;
    let fog = |shift: f32, keyed: bool| -> Vec<GpuFragment> {
        (0..40 * n)
            .map(|i| {
                let f = GpuFragment::new(i % n, [0.01, 0.02, 0.005, 0.03], (i / n) as f32 + shift);
                if keyed { f.with_key(1000 + i / n) } else { f }
            })
            .collect()
    };
    let (plain, keyed) = (fog(0.0, false), fog(0.0, true));
    let (plain_moved, keyed_moved) = (fog(0.001, false), fog(0.001, true));
    for layers in [Layers::Mlab(2), Layers::Mlab(8), Layers::Hybrid(2)] {
        for arith in ArithKind::ALL {
            let c = Compositor::new(&gpu, layers, arith, Layout::Spans).expect("compositor");
            let run = |frags: &[GpuFragment]| {
                check(&c, layers, arith, Layout::Spans, w, h, frags);
                c.composite(w, h, frags).expect("gpu")
            };
            let (p, k, pm, km) = (run(&plain), run(&keyed), run(&plain_moved), run(&keyed_moved));
            if arith == ArithKind::Paper {
                assert_eq!(p, k, "{layers:?}: Paper has no dither, no key changes a byte");
            } else {
                assert_ne!(p, k, "{layers:?}: the keys seed Unbiased's dithers");
                // With keys, the move changes no color byte (the dithers do not re-roll); with
                // content keys it does.
                assert_eq!(colors(&k), colors(&km), "{layers:?}: keyed fog moved");
                assert_ne!(colors(&p), colors(&pm), "{layers:?}: unkeyed fog moved");
            }
        }
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_paper_tails_count_and_alpha_saturate_on_the_gpu_as_on_the_cpu() {
    let Some(gpu) = gpu("paper_tail_saturation") else {
        return;
    };
    // 70 000 opaque fragments into one pixel: PaperTail's 16-bit count and alpha saturate.
    let frags: Vec<GpuFragment> = (0..70_000u32)
        .map(|i| GpuFragment::new(0, [0.2, 0.1, 1.0, 1.0], (i % 5000) as f32 + 1.0))
        .collect();
    for arith in ArithKind::ALL {
        let c = Compositor::new(&gpu, Layers::Hybrid(1), arith, Layout::PixelMajor).expect("compositor");
        check(&c, Layers::Hybrid(1), arith, Layout::PixelMajor, 1, 1, &frags);
        let words = c.composite(1, 1, &frags).expect("gpu");
        if arith == ArithKind::Paper {
            assert_eq!(words[3], u32::MAX, "alpha and count saturated at 65535");
        }
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn bands_split_by_the_binding_limit_give_the_same_words() {
    let Some(gpu) = gpu("bands") else { return };
    let mut rng = Rng(99);
    let (w, h, frags) = banded_stream(&mut rng);
    for layout in [Layout::PixelMajor, Layout::Spans] {
        let mut c = Compositor::new(&gpu, Layers::Hybrid(3), ArithKind::Unbiased, layout).expect("compositor");
        same_in_bands(&mut c, |c| c.composite(w, h, &frags).expect("rows"));
        check(&c, Layers::Hybrid(3), ArithKind::Unbiased, layout, w, h, &frags);
        // One line with more fragments than a binding holds is a typed error.
        let crowded: Vec<GpuFragment> = (0..1000).map(|_| rng.fragment(0)).collect();
        assert!(matches!(
            c.composite(w, h, &crowded),
            Err(GpuError::LineTooLarge { y: 0, .. })
        ));
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn bad_input_is_a_typed_error_not_a_panic() {
    let Some(gpu) = gpu("errors") else { return };
    let c = Compositor::new(&gpu, Layers::Mlab(2), ArithKind::Paper, Layout::Spans).expect("compositor");
    let ok = GpuFragment::new(0, [0.1, 0.1, 0.1, 0.5], 1.0);
    let bad = |f: GpuFragment| c.composite(4, 4, &[ok, f]);
    assert_eq!(
        bad(GpuFragment { pixel: 16, ..ok }),
        Err(GpuError::PixelOutOfRange {
            index: 1,
            pixel: 16,
            pixels: 16
        })
    );
    for (f, e) in [
        (GpuFragment { depth: f32::NAN, ..ok }, FragmentError::NanDepth),
        (
            GpuFragment {
                depth: f32::INFINITY,
                ..ok
            },
            FragmentError::InfiniteDepth,
        ),
        (
            GpuFragment {
                rgba: [0.1, 0.1, 0.1, 1.5],
                ..ok
            },
            FragmentError::AlphaOutOfRange,
        ),
        (
            GpuFragment {
                rgba: [-0.1, 0.1, 0.1, 0.5],
                ..ok
            },
            FragmentError::NegativeColor,
        ),
        (
            GpuFragment {
                rgba: [1.1, 0.1, 0.1, 0.5],
                ..ok
            },
            FragmentError::ColorAboveOne,
        ),
    ] {
        assert_eq!(bad(f), Err(GpuError::Fragment { index: 1, error: e }));
    }
    assert!(matches!(
        c.composite(u32::MAX, 2, &[]),
        Err(GpuError::FrameTooLarge { .. })
    ));
    assert!(matches!(
        Compositor::new(&gpu, Layers::Mlab(9), ArithKind::Paper, Layout::Spans),
        Err(GpuError::UnsupportedLayers(Layers::Mlab(9)))
    ));
    assert!(matches!(
        wgsl::hybrid(0, ArithKind::Paper),
        Err(GpuError::UnsupportedLayers(_))
    ));
    // Empty frames and empty streams are fine: cleared storage.
    assert_eq!(c.composite(0, 0, &[]), Ok(vec![]));
    assert_eq!(c.composite(0, 5, &[]), Ok(vec![]));
    assert!(matches!(
        c.composite(0, 5, &[ok]),
        Err(GpuError::PixelOutOfRange { index: 0, .. })
    ));
    assert_eq!(
        c.composite(3, 1, &[]).expect("empty"),
        cpu::composite(Layers::Mlab(2), ArithKind::Paper, Layout::Spans, 3, 1, &[]).expect("cpu")
    );
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_exported_wgsl_is_what_the_compositor_runs() {
    let Some(gpu) = gpu("exported_wgsl") else { return };
    for layers in all_layers() {
        for arith in ArithKind::ALL {
            let c = Compositor::new(&gpu, layers, arith, Layout::Spans).expect("compositor");
            let library = match layers {
                Layers::Mlab(m) => wgsl::mlab(m, arith),
                Layers::Hybrid(k) => wgsl::hybrid(k, arith),
            }
            .expect("library");
            assert_eq!(c.source(), wgsl::compositor(layers, arith).expect("text"));
            assert!(c.source().starts_with(&library), "{layers:?} {arith:?}");
            assert!(library.starts_with(wgsl::KERNEL));
            // The resolve the compositor runs is the exported one (HT: wgsl::HT_RESOLVE).
            match layers {
                Layers::Mlab(_) => assert!(library.ends_with(wgsl::MLAB_INSERT)),
                Layers::Hybrid(_) => assert!(library.ends_with(&format!("{}\n{}", wgsl::HT_INSERT, wgsl::HT_RESOLVE))),
            }
        }
    }
    // The library alone (no entry point) is valid WGSL a renderer can include.
    let device = gpu.device();
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    for src in [wgsl::mlab(8, ArithKind::Unbiased), wgsl::hybrid(1, ArithKind::Paper)] {
        let _module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: None,
            source: wgpu::ShaderSource::Wgsl(src.expect("text").into()),
        });
    }
    assert!(pollster::block_on(scope.pop()).is_none());
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn pixels_with_more_fragments_than_one_dispatch_takes_continue_in_the_next() {
    let Some(gpu) = gpu("long_pixels") else { return };
    // Pixel 0: 100 000 fragments (lavapipe ends an invocation's loops after 65,535 iterations in
    // all, inner loops included: dispatches of 32,766 fragments for M = 1 down to 6,551 for
    // K = 8, 4 to 16 of them); the others a few, so later dispatches leave them untouched.
    let mut rng = Rng(5);
    let mut frags: Vec<GpuFragment> = (0..100_000).map(|_| rng.fragment(0)).collect();
    frags.extend((0..500).map(|_| rng.fragment_in(6)));
    // Most with stable keys: every dispatch seeds the merges with the same hashes as the CPU.
    let frags = rng.keyed(frags);
    // A stream in which every fragment shows in the bytes (in the random one, the nearest
    // opaque fragments hide most of the others): pixel 0 receives 100 000 coplanar fragments of
    // alpha 0 (T = 255: the merges add colors exactly, in both arithmetics), blue 1/255 each
    // (visible: each reaches HT's tail and its count), red 1/255 on every 400th and green on
    // every 397th. The red and green bytes (MLAB's rows, HT's tail sums) count those, so a
    // fragment lost anywhere changes a byte.
    let counting: Vec<GpuFragment> = (0..100_000u32)
        .map(|i| {
            let mark = |k| if i % k == 0 { 1.0 / 255.0 } else { 0.0 };
            GpuFragment::new(0, [mark(400), mark(397), 1.0 / 255.0, 0.0], 1.0)
        })
        .collect();
    for layers in all_layers() {
        for arith in ArithKind::ALL {
            let c = Compositor::new(&gpu, layers, arith, Layout::PixelMajor).expect("compositor");
            check(&c, layers, arith, Layout::PixelMajor, 1, 1, &counting);
            if matches!(layers, Layers::Mlab(1 | 5 | 8) | Layers::Hybrid(2 | 8)) {
                check(&c, layers, arith, Layout::PixelMajor, 3, 2, &frags);
            }
        }
    }
}

#[path = "../../examples/common/raster.rs"]
mod raster;

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_rasterizer_examples_torus_gives_the_same_rows_on_the_gpu() {
    let Some(gpu) = gpu("torus") else { return };
    let (w, h) = (160, 120);
    let mut frags = Vec::new();
    for t in &raster::scene(w, h, 48, 24) {
        raster::rasterize(t, w, h, |x, y, z| {
            let f = mlab::Fragment::straight(mlab::glam::Vec3::from_array(t.color), t.alpha, z).expect("valid");
            let c = f.color();
            frags.push(GpuFragment::new(y * w + x, [c.x, c.y, c.z, f.alpha()], z));
        });
    }
    assert!(frags.len() > 10_000);
    // The same fragments keyed by their triangle, as a renderer keys them by primitive id.
    let mut keyed = Vec::new();
    for (prim, t) in (0u32..).zip(&raster::scene(w, h, 48, 24)) {
        raster::rasterize(t, w, h, |x, y, z| {
            let f = mlab::Fragment::straight(mlab::glam::Vec3::from_array(t.color), t.alpha, z).expect("valid");
            let c = f.color();
            keyed.push(GpuFragment::new(y * w + x, [c.x, c.y, c.z, f.alpha()], z).with_key(prim));
        });
    }
    for layers in [Layers::Mlab(2), Layers::Mlab(4), Layers::Hybrid(3)] {
        for arith in ArithKind::ALL {
            let c = Compositor::new(&gpu, layers, arith, Layout::Spans).expect("compositor");
            check(&c, layers, arith, Layout::Spans, w, h, &frags);
            check(&c, layers, arith, Layout::Spans, w, h, &keyed);
        }
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn mlab_rgba8_from_the_gpus_integer_resolve_is_the_kernels() {
    let Some(gpu) = gpu("rgba8") else { return };
    let mut rng = Rng(0x5247_4241);
    let backgrounds = [
        Background::Transparent,
        Background::Opaque(Vec3::new(0.9, 0.9, 0.85)),
        Background::Opaque(Vec3::new(0.0, 1.0, 128.0 / 255.0)),
        Background::Opaque(Vec3::new(f32::NAN, -1.0, 2.0)),
        Background::Opaque(Vec3::new(1e-40, 0.5 / 255.0, f32::INFINITY)),
    ];
    let mut total = 0;
    for m in Layers::SIZES {
        for arith in ArithKind::ALL {
            for layout in [Layout::Spans, Layout::PixelMajor] {
                let c = Compositor::new(&gpu, Layers::Mlab(m), arith, layout).expect("compositor");
                for (w, h, n) in [(37, 11, 6_000), (8, 2, 800), (1, 1, 50)] {
                    let mut frags = random_stream(&mut rng, w, h, n);
                    if w != 8 {
                        frags = rng.keyed(frags);
                    }
                    let bg = backgrounds[rng.below(backgrounds.len() as u32) as usize];
                    let (words, image) = c.composite_rgba8(w, h, &frags, bg).expect("gpu");
                    assert_eq!(words, c.composite(w, h, &frags).expect("gpu rows"));
                    let want = cpu::resolve_rgba8(Layers::Mlab(m), arith, w, h, &frags, bg).expect("cpu");
                    assert_eq!(image.len(), want.len());
                    if let Some(i) = (0..image.len()).find(|&i| image[i] != want[i]) {
                        panic!(
                            "M = {m} {arith:?} {layout:?} {w}x{h} {bg:?}: pixel {i}: gpu {:?}, cpu {:?}",
                            image[i], want[i]
                        );
                    }
                    total += n;
                }
            }
        }
    }
    println!("rgba8: {total} fragments, identical images");
    // Bands give the same image (MLAB here, HT below: HT's RGBA8 is tests/ht_rgba8.rs).
    let (w, h, frags) = banded_stream(&mut rng);
    let bg = Background::Opaque(Vec3::new(0.2, 0.4, 0.6));
    let mut c = Compositor::new(&gpu, Layers::Mlab(4), ArithKind::Unbiased, Layout::Spans).expect("compositor");
    same_in_bands(&mut c, |c| c.composite_rgba8(w, h, &frags, bg).expect("rgba8"));
    let mut ht = Compositor::new(&gpu, Layers::Hybrid(3), ArithKind::Unbiased, Layout::Spans).expect("compositor");
    let (_, image) = same_in_bands(&mut ht, |c| c.composite_rgba8(w, h, &frags, bg).expect("rgba8"));
    assert_eq!(
        image,
        cpu::resolve_rgba8(Layers::Hybrid(3), ArithKind::Unbiased, w, h, &frags, bg).expect("cpu")
    );
}

// The sort by pixel on the GPU (`Sort::Gpu`). The default is `Sort::Cpu` on a software adapter
// (lavapipe: every test above goes through the CPU sort there), so this test sets it.

/// The stable order by pixel: the indices the compositor must insert in.
fn stable_order(frags: &[GpuFragment]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..frags.len() as u32).collect();
    order.sort_by_key(|&i| frags[i as usize].pixel); // `sort_by_key` is stable
    order
}

/// Coplanar (two depths), light fragments (alpha 0.07-0.12: forty leave the pixel visible
/// behind them) of distinct colors, `per` for each of `w * h` pixels, pixels in shuffled order:
/// MLAB's merges make the rows depend on the order within a pixel.
fn shuffled_coplanar(rng: &mut Rng, w: u32, h: u32, per: u32) -> Vec<GpuFragment> {
    let mut pixels: Vec<u32> = (0..w * h).flat_map(|p| std::iter::repeat_n(p, per as usize)).collect();
    for i in (1..pixels.len()).rev() {
        pixels.swap(i, rng.below(i as u32 + 1) as usize);
    }
    pixels
        .into_iter()
        .map(|pixel| {
            let a = 0.07 + 0.05 * rng.unit();
            GpuFragment::new(
                pixel,
                [rng.unit() * a, rng.unit() * a, rng.unit() * a, a],
                rng.below(2) as f32,
            )
        })
        .collect()
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_gpu_sort_gives_the_stable_order_and_the_cpus_rows() {
    let Some(gpu) = gpu("gpu_sort") else { return };
    let mut rng = Rng(0x736f_7274);
    let shuffled = shuffled_coplanar(&mut rng, 37, 11, 40); // 16,280: not a power of two
    let one = vec![rng.fragment(17)];
    let odd = random_stream(&mut rng, 5, 3, 4_021);
    let keyed = rng.keyed(shuffled.clone());
    let crowded: Vec<GpuFragment> = (0..100_000).map(|_| rng.fragment(0)).collect();
    let cases: [(&str, u32, u32, &[GpuFragment]); 6] = [
        ("shuffled", 37, 11, &shuffled),
        ("shuffled, keyed", 37, 11, &keyed),
        ("odd count", 5, 3, &odd),
        ("one", 37, 11, &one),
        ("none", 37, 11, &[]),
        ("one pixel", 1, 1, &crowded),
    ];
    for layers in [Layers::Mlab(2), Layers::Hybrid(3)] {
        let mut c = Compositor::new(&gpu, layers, ArithKind::Unbiased, Layout::Spans).expect("compositor");
        let software = gpu.adapter_info().device_type == wgpu::DeviceType::Cpu;
        assert_eq!(c.sort(), if software { Sort::Cpu } else { Sort::Gpu });
        c.set_sort(Sort::Gpu);
        for (name, w, h, frags) in cases {
            let want = stable_order(frags);
            assert_eq!(c.order(w, h, frags).expect("gpu order"), want, "{name}");
            check(&c, layers, ArithKind::Unbiased, Layout::Spans, w, h, frags);
            c.set_sort(Sort::Cpu);
            assert_eq!(c.order(w, h, frags).expect("cpu order"), want, "{name}, Sort::Cpu");
            check(&c, layers, ArithKind::Unbiased, Layout::Spans, w, h, frags);
            c.set_sort(Sort::Gpu);
        }
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn the_gpu_sort_over_several_bands_is_the_stable_order() {
    let Some(gpu) = gpu("gpu_sort_bands") else { return };
    let mut rng = Rng(0x6261_6e64);
    // 30 x 40 with 8 fragments per pixel: about 7.7 KB of fragments per line, so a 16 KiB
    // binding cap (`BAND_BYTES`) gives bands of two lines (20 bands), each sorted on its own.
    let frags = shuffled_coplanar(&mut rng, 30, 40, 8);
    for layout in [Layout::PixelMajor, Layout::Spans] {
        let mut c = Compositor::new(&gpu, Layers::Mlab(3), ArithKind::Paper, layout).expect("compositor");
        c.set_sort(Sort::Gpu);
        let order = same_in_bands(&mut c, |c| c.order(30, 40, &frags).expect("order"));
        assert_eq!(order, stable_order(&frags));
        check(&c, Layers::Mlab(3), ArithKind::Paper, layout, 30, 40, &frags);
    }
}

#[test]
#[cfg_attr(
    mlab_gpu_no_driver,
    ignore = "no Vulkan driver when mlab-gpu was built (apt-get install mesa-vulkan-drivers libvulkan1; CI=true fails instead)"
)]
fn an_unstable_sort_would_fail_these_tests() {
    let Some(gpu) = gpu("unstable_sort") else { return };
    let mut rng = Rng(0x756e_7374);
    let (w, h) = (37, 11);
    let frags = shuffled_coplanar(&mut rng, w, h, 40);
    let layers = Layers::Mlab(2);
    let want = cpu::composite(layers, ArithKind::Unbiased, Layout::Spans, w, h, &frags).expect("cpu");
    // On the CPU: swapping two fragments in the middle of pixel 0 (its rows are full, so both
    // are merged) changes the kernel's rows.
    let at: Vec<usize> = (0..frags.len()).filter(|&i| frags[i].pixel == 0).collect();
    let mut swapped = frags.clone();
    swapped.swap(at[at.len() / 2 - 1], at[at.len() / 2]);
    let other = cpu::composite(layers, ArithKind::Unbiased, Layout::Spans, w, h, &swapped).expect("cpu");
    assert!(other != want, "the order within a pixel changes the kernel's bytes");
    // On the GPU: the stable sort gives the kernel's rows; comparing pixels alone (an unstable
    // sort) reorders fragments within pixels, and the comparison of the rows sees it.
    let mut c = Compositor::new(&gpu, layers, ArithKind::Unbiased, Layout::Spans).expect("compositor");
    c.set_sort(Sort::Gpu);
    assert_eq!(c.composite(w, h, &frags).expect("stable"), want);
    c.set_stable_sort_for_tests(false);
    let order = c.order(w, h, &frags).expect("unstable order");
    let mut by_pixel = order.clone();
    by_pixel.sort_by_key(|&i| frags[i as usize].pixel);
    assert_eq!(order, by_pixel, "still sorted by pixel");
    assert_ne!(order, stable_order(&frags), "but not in submission order within pixels");
    let rows = c.composite(w, h, &frags).expect("unstable");
    let differ = (0..rows.len() / 2)
        .filter(|&s| rows[2 * s..2 * s + 2] != want[2 * s..2 * s + 2])
        .count();
    println!("unstable sort: {differ} of {} slots differ", rows.len() / 2);
    assert!(differ > 0, "an unstable sort changes the rows");
}
