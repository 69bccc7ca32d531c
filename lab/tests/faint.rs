//! Issue 9 measurements: fragments per covered pixel and the HT tail sums, against the
//! kernel and hand-computed cases.

use mlab::{HybridFramebuffer, Row, Tail};
use oit_lab::faint::{TailSums, depth, quantile, tail_sums};
use oit_lab::methods::Frame;
use oit_lab::scenes::Scene;
use oit_lab::stream::{Frag, Stream};

fn stream(w: u32, h: u32, frags: &[(u32, f32, [f32; 3], f32)]) -> Stream {
    Stream {
        width: w,
        height: h,
        background: [1.0; 3],
        frags: frags
            .iter()
            .map(|&(pixel, depth, color, alpha)| Frag {
                pixel,
                depth,
                color,
                alpha,
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
    let d = depth(&Frame::new(&s));
    assert_eq!((d.covered, d.mean, d.max), (2, 2.0, 3));
    let empty = stream(2, 2, &[]);
    let d = depth(&Frame::new(&empty));
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
    let f = Frame::new(&s);
    let all = tail_sums(&f, 0).unwrap()[0];
    assert_eq!(
        all,
        TailSums {
            color: [26 + 255 + 128, 255 + 26, 128 + 255 + 26],
            alpha: 51 + 255 + 51,
            count: 4,
        }
    );
    // K = 2 keeps z 1 and z 2 in the head: z 3 (invisible), 4, 5 remain.
    let beyond2 = tail_sums(&f, 2).unwrap()[0];
    assert_eq!(
        beyond2,
        TailSums {
            color: [26, 0, 128 + 26],
            alpha: 51,
            count: 2,
        }
    );
    assert_eq!(tail_sums(&f, 5).unwrap()[0], TailSums::default());
}

#[test]
fn tail_sums_equal_the_kernel_tail_where_it_does_not_saturate() {
    for (sc, w, h) in [(Scene::Splats, 64, 36), (Scene::Fog, 24, 14), (Scene::Hair, 64, 36)] {
        let s = sc.generate(w, h, 3);
        let f = Frame::new(&s);
        let sums = tail_sums(&f, 3).unwrap();
        let mut storage = vec![Row::EMPTY; HybridFramebuffer::<3>::rows_needed(w, h).unwrap()];
        let mut fb = HybridFramebuffer::<3>::new(&mut storage, w, h).unwrap();
        fb.clear();
        for x in &s.frags {
            fb.insert(x.pixel % w, x.pixel / w, &x.to_kernel().unwrap()).unwrap();
        }
        let mut saturated = 0;
        for p in 0..s.pixels() {
            let t = sums[p];
            let want = Tail::from_sums(
                t.color.map(|c| c.min(u32::MAX as u64) as u32),
                t.alpha.min(u32::MAX as u64) as u32,
                t.count.min(u32::MAX as u64) as u32,
            );
            let got = fb.pixel(p as u32 % w, p as u32 / w).unwrap().1;
            assert_eq!(got, want, "{} pixel {p}", sc.name());
            saturated += usize::from(t.color.iter().any(|&c| c > 1023));
        }
        if sc == Scene::Splats {
            assert!(saturated > 0, "SPLATS should saturate the paper's color sums somewhere");
        }
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
