//! Issue 9 measurements: fragments per covered pixel and the HT tail sums, against the
//! kernel and hand-computed cases.

use mlab::hybrid::{PaperTail, TailFormat};
use mlab::{Arithmetic, Framebuffer, HybridFramebuffer, Paper, Row, Unbiased};
use oit_lab::methods::depth::depth;
use oit_lab::methods::{Arith, BinnedStream, Image, Method, hybrid_with};
use oit_lab::metrics::{compare, compare_covered};
use oit_lab::out::table::spread;
use oit_lab::scenes::Scene;
use oit_lab::stream::{Frag, Stream};
use oit_lab::study::faint::{TailSums, quantile, run_stream, tail_sums};

fn stream(w: u32, h: u32, frags: &[(u32, f32, [f32; 3], f32)]) -> Stream {
    Stream {
        width: w,
        height: h,
        background: [1.0; 3],
        frags: frags
            .iter()
            .enumerate()
            .map(|(i, &(pixel, depth, color, alpha))| Frag {
                pixel,
                depth,
                color,
                alpha,
                // Each fragment its own primitive.
                prim: i as u32,
            })
            .collect(),
    }
}

#[test]
fn depth_counts_only_covered_pixels() {
    // 2x2: pixel 0 has 3 fragments, pixel 3 has 1, pixels 1 and 2 none.
    let s = stream(
        2,
        2,
        &[
            (0, 1.0, [0.1; 3], 0.5),
            (3, 1.0, [0.1; 3], 0.5),
            (0, 2.0, [0.1; 3], 0.5),
            (0, 3.0, [0.1; 3], 0.5),
        ],
    );
    let d = depth(&BinnedStream::new(&s));
    assert_eq!((d.covered, d.mean, d.max), (2, 2.0, 3));
    let empty = stream(2, 2, &[]);
    let d = depth(&BinnedStream::new(&empty));
    assert_eq!((d.covered, d.mean, d.max), (0, 0.0, 0));
}

#[test]
fn tail_sums_skip_the_nearest_k_and_invisible_rows() {
    // One pixel, submitted far to near-ish; alpha 0.2 -> byte 51, color 0.1 -> 26 (25.5 up),
    // 0.5 -> 128 (127.5 up), 1.0 -> 255.
    let s = stream(
        1,
        1,
        &[
            (0, 4.0, [0.1, 0.0, 0.5], 0.2),
            (0, 1.0, [1.0, 1.0, 1.0], 1.0),
            (0, 3.0, [0.0, 0.0, 0.0], 0.0), // invisible: not counted
            (0, 2.0, [0.5, 0.1, 0.0], 0.2),
            (0, 5.0, [0.0, 0.0, 0.1], 0.0), // additive light: counted
        ],
    );
    let f = BinnedStream::new(&s);
    let all = tail_sums(&f, 0, Arith::Paper).unwrap()[0];
    assert_eq!(
        all,
        TailSums {
            color: [26 + 255 + 128, 255 + 26, 128 + 255 + 26],
            alpha: 51 + 255 + 51,
            count: 4,
        }
    );
    // K = 2 keeps z 1 and z 2 in the head: z 3 (invisible), 4, 5 remain.
    let beyond2 = tail_sums(&f, 2, Arith::Paper).unwrap()[0];
    assert_eq!(
        beyond2,
        TailSums {
            color: [26, 0, 128 + 26],
            alpha: 51,
            count: 2,
        }
    );
    assert_eq!(tail_sums(&f, 5, Arith::Paper).unwrap()[0], TailSums::default());
    // The unbiased quantization dithers: each byte is the floor or the ceiling of the exact
    // value, and exact values stay exact (1.0 -> 255, 0 -> 0).
    let u = tail_sums(&f, 0, Arith::Unbiased).unwrap()[0];
    assert_eq!(u.count, 4);
    assert!((25 + 255 + 127..=26 + 255 + 128).contains(&u.color[0]), "{u:?}");
    assert!((2 * 51 + 255..=2 * 52 + 255).contains(&u.alpha), "{u:?}");
}

/// The kernel's HT tails after every fragment of `s` in submission order, arithmetic `A`.
fn kernel_tails<A: Arithmetic>(s: &Stream) -> Vec<A::Tail> {
    let (w, h) = (s.width, s.height);
    let mut storage = vec![Row::EMPTY; HybridFramebuffer::<3, A>::rows_needed(w, h).unwrap()];
    let mut fb = HybridFramebuffer::<3, A>::new(&mut storage, w, h).unwrap();
    fb.clear();
    for x in &s.frags {
        fb.insert(x.pixel % w, x.pixel / w, &x.to_kernel().unwrap()).unwrap();
    }
    (0..w * h).map(|p| fb.pixel(p % w, p / w).unwrap().1).collect()
}

fn clamp32(v: u64) -> u32 {
    v.min(u32::MAX as u64) as u32
}

#[test]
fn tail_sums_equal_the_kernel_tail_where_it_does_not_saturate() {
    for (sc, w, h) in [(Scene::Splats, 64, 36), (Scene::Fog, 24, 14), (Scene::Hair, 64, 36)] {
        let s = sc.generate(w, h, 3);
        let f = BinnedStream::new(&s);
        let (mut paper_saturated, mut unbiased_saturated) = (0usize, 0usize);
        let sums = tail_sums(&f, 3, Arith::Paper).unwrap();
        for (p, (t, got)) in sums.iter().zip(kernel_tails::<Paper>(&s)).enumerate() {
            let want = PaperTail::from_sums(t.color.map(clamp32), clamp32(t.alpha), clamp32(t.count));
            assert_eq!(got, want, "{} pixel {p} (paper)", sc.name());
            paper_saturated += usize::from(got.saturated());
        }
        let sums = tail_sums(&f, 3, Arith::Unbiased).unwrap();
        for (p, (t, got)) in sums.iter().zip(kernel_tails::<Unbiased>(&s)).enumerate() {
            let want =
                <Unbiased as Arithmetic>::Tail::from_sums(t.color.map(clamp32), clamp32(t.alpha), clamp32(t.count));
            assert_eq!(got, want, "{} pixel {p} (unbiased)", sc.name());
            unbiased_saturated += usize::from(got.saturated());
        }
        if sc == Scene::Splats {
            assert!(
                paper_saturated > 0,
                "SPLATS should saturate the paper's color sums somewhere"
            );
        }
        // The wider tail saturates far less (at this tiny size SPLATS has up to 363 fragments
        // in a pixel, and a blue sum passes 8191 in two pixels).
        // HAIR's tie (issue 10: hundreds of strands over a pixel) passes even the wider
        // fields: at this size 67 saturated pixels against 336 (measured), so a factor of 4
        // there, 10 elsewhere.
        let factor = if sc == Scene::Hair { 4 } else { 10 };
        assert!(
            unbiased_saturated * factor <= paper_saturated.max(1),
            "{}: {unbiased_saturated} saturated tails (unbiased) against {paper_saturated} (paper)",
            sc.name()
        );
    }
}

#[test]
fn quantile_is_nearest_rank() {
    let mut v = vec![5, 1, 4, 2, 3];
    assert_eq!(quantile(&mut v, 0.0), 1);
    assert_eq!(quantile(&mut v, 0.2), 1);
    assert_eq!(quantile(&mut v, 0.21), 2);
    assert_eq!(quantile(&mut v, 0.5), 3);
    assert_eq!(quantile(&mut v, 1.0), 5);
    assert_eq!(quantile(&mut v, f64::NAN), 5);
    assert_eq!(quantile(&mut [], 0.5), 0);
}

fn image(rgb: Vec<[f32; 3]>, vis: Vec<f32>) -> Image {
    Image {
        width: rgb.len() as u32,
        height: 1,
        rgb,
        vis,
    }
}

#[test]
fn covered_metrics_by_hand() {
    // Pixel 0 covered, every channel off by 0.1; pixel 1 covered, exact color; pixel 2 not
    // covered, off by 0.5 (ignored). Covered: 3 errors of 0.1 over 6 values:
    // RMSE = sqrt(0.03 / 6), PSNR = 20 log10(1 / RMSE) = 10 log10(200) = 23.0103 dB.
    let reference = image(vec![[0.5; 3], [0.2; 3], [0.0; 3]], vec![0.5, 0.25, 1.0]);
    let test = image(vec![[0.6; 3], [0.2; 3], [0.5; 3]], vec![0.75, 0.125, 0.0]);
    let c = compare_covered(&reference, &test, &[true, true, false]);
    assert_eq!(c.pixels, 2);
    assert!((c.rmse - (0.03f64 / 6.0).sqrt()).abs() < 1e-7, "{}", c.rmse);
    assert!((c.psnr - 10.0 * 200f64.log10()).abs() < 1e-5, "{}", c.psnr);
    // Visibility: +0.25 and -0.125 (exact in binary): mean +0.0625, worst +0.25.
    assert_eq!(c.vis_bias, 0.0625);
    assert_eq!(c.vis_worst, 0.25);
    assert_eq!(c.vis_abs, 0.1875);
    // The uncovered pixel counts in the whole-image PSNR, not here.
    assert!(compare(&reference, &test, false).psnr < c.psnr - 3.0);
    // The worst keeps its sign.
    let c = compare_covered(&reference, &test, &[false, true, false]);
    assert_eq!((c.vis_bias, c.vis_worst, c.vis_abs), (-0.125, -0.125, 0.125));
    // Nothing covered: no error, no bias.
    let c = compare_covered(&reference, &test, &[false; 3]);
    assert_eq!(
        (c.pixels, c.rmse, c.psnr, c.vis_bias, c.vis_worst),
        (0, 0.0, f64::INFINITY, 0.0, 0.0)
    );
    // Display clamping as in `compare`: 1.5 against 1.0 is no error.
    let c = compare_covered(
        &image(vec![[1.0; 3]], vec![0.0]),
        &image(vec![[1.5; 3]], vec![0.0]),
        &[true],
    );
    assert_eq!(c.psnr, f64::INFINITY);
}

#[test]
fn noise_is_the_high_pass_of_the_error_by_hand() {
    let grid = |f: &dyn Fn(usize) -> f32| Image {
        width: 3,
        height: 3,
        rgb: (0..9).map(|p| [f(p); 3]).collect(),
        vis: vec![0.0; 9],
    };
    let reference = grid(&|_| 0.25);
    // A constant error is no noise.
    let constant = grid(&|_| 0.375);
    let c = compare_covered(&reference, &constant, &[true; 9]);
    assert_eq!((c.rmse, c.noise), (0.125, 0.0));
    // An error d = 0.5 at the centre only: the centre's 3x3 mean is d/9 (high pass 8d/9), a
    // corner's 2x2 block holds the centre (d/4, high pass -d/4), an edge's 2x3 block too
    // (d/6, high pass -d/6). RMS over the 9 pixels (channels equal):
    // sqrt((64/81 + 4/16 + 4/36) d^2 / 9).
    let spike = grid(&|p| if p == 4 { 0.75 } else { 0.25 });
    let c = compare_covered(&reference, &spike, &[true; 9]);
    let d = 0.5f64;
    let want = ((64.0 / 81.0 + 4.0 / 16.0 + 4.0 / 36.0) * d * d / 9.0).sqrt();
    assert!((c.noise - want).abs() < 1e-12, "{} {want}", c.noise);
    // Uncovered pixels take no part: with only the centre covered its block is itself.
    let mut only_centre = [false; 9];
    only_centre[4] = true;
    assert_eq!(compare_covered(&reference, &spike, &only_centre).noise, 0.0);
}

#[test]
fn flip_is_zero_for_identical_images_and_grows_with_the_difference() {
    let a = Image {
        width: 16,
        height: 16,
        rgb: vec![[0.5; 3]; 256],
        vis: vec![1.0; 256],
    };
    let mut b = a.clone();
    let mut c = a.clone();
    for p in 0..128 {
        b.rgb[p] = [0.55; 3];
        c.rgb[p] = [0.9; 3];
    }
    assert_eq!(compare(&a, &a, true).flip, Some(0.0));
    let (fb, fc) = (compare(&a, &b, true).flip.unwrap(), compare(&a, &c, true).flip.unwrap());
    assert!(0.0 < fb && fb < fc && fc <= 1.0, "{fb} {fc}");
}

#[test]
fn saturated_tails_by_hand() {
    // K = 0, paper tail (colors saturate at 1023): pixel 0 gets 5 fragments of color 1
    // (5 x 255 = 1275 > 1023), pixel 1 gets 4 (1020 < 1023), pixel 2 one of alpha 1 and
    // color 0.
    let mut frags = Vec::new();
    for i in 0..5 {
        frags.push((0, 1.0 + i as f32, [1.0, 0.0, 0.0], 1.0));
    }
    for i in 0..4 {
        frags.push((1, 1.0 + i as f32, [0.0, 0.0, 1.0], 1.0));
    }
    frags.push((2, 1.0, [0.0; 3], 1.0));
    let s = stream(3, 1, &frags);
    let f = BinnedStream::new(&s);
    let (_, saturated) = hybrid_with(0, Arith::Paper, &f).unwrap();
    assert_eq!(saturated, 1);
    // One head row takes one fragment per pixel out of the tail: none saturates.
    let (_, saturated) = hybrid_with(1, Arith::Paper, &f).unwrap();
    assert_eq!(saturated, 0);
    // The report counts them per method.
    let run = run_stream(
        Scene::Fog,
        0,
        &s,
        &[Method::HybridWith(0, Arith::Paper), Method::Over],
        false,
    )
    .unwrap();
    assert_eq!(run.measures[0].saturated, Some(1));
    assert_eq!(run.measures[1].saturated, None);
    assert_eq!((run.depth.covered, run.depth.max), (3, 5));
}

#[test]
fn spread_prints_median_min_max() {
    assert_eq!(spread(&[3.0, 1.0, 2.0], 1, false), "2.0 [1.0, 3.0]");
    assert_eq!(spread(&[4.0, 1.0, 2.0, 3.0], 1, false), "2.5 [1.0, 4.0]");
    assert_eq!(spread(&[0.25], 2, true), "+0.25");
    assert_eq!(spread(&[f64::INFINITY, 1.0, 2.0], 0, false), "2 [1, inf]");
    assert_eq!(spread(&[f64::NAN], 1, false), "-");
    assert_eq!(spread(&[], 1, false), "-");
}

#[test]
fn report_has_every_scene_and_method() {
    let methods = oit_lab::methods::catalog::faint();
    // OVER, then MLAB 1, 2, 4, 8 and HT 0, 1, 3, 7, each with both arithmetics.
    assert_eq!(methods.len(), 17);
    assert_eq!(
        methods
            .iter()
            .map(|m| m.bytes_per_pixel(&BinnedStream::new(&stream(1, 1, &[]))))
            .sum::<f64>(),
        8.0 + 4.0 * 8.0 * (1 + 2 + 4 + 8) as f64
    );
    let mut runs = Vec::new();
    for (sc, seed) in [(Scene::Glass, 1), (Scene::Glass, 2), (Scene::Splats, 1)] {
        let s = sc.generate(32, 18, seed);
        runs.push(run_stream(sc, seed, &s, &methods, false).unwrap());
    }
    let full = oit_lab::study::faint::full_table(&runs);
    // Header, separator, one row per method and scene, a blank line and the HT naming note.
    assert_eq!(full.lines().count(), 2 + 2 * methods.len() + 2);
    assert!(full.contains("the paper's HT K+1"));
    assert!(full.contains("| MLAB 4 unbiased | 32 |") && full.contains("| HT 3 paper | 32 |"));
    let head = oit_lab::study::faint::headline_table(&runs);
    assert_eq!(head.lines().count(), 2 + 2 + 2);
    assert!(head.starts_with("| scene | frags / covered px (mean; max) | OVER unsorted | MLAB 4 paper |"));
    // Two seeds of GLASS give a spread, one of SPLATS a single value.
    let glass = head.lines().find(|l| l.starts_with("| GLASS")).unwrap();
    let splats = head.lines().find(|l| l.starts_with("| SPLATS")).unwrap();
    assert!(glass.contains(" ["), "{glass}");
    assert!(!splats.contains(" ["), "{splats}");
}
