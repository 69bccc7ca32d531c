//! `oit-lab peers` (issue 25): MLAB against the bounded-memory methods a renderer would pick
//! today (moment-based OIT, K-closest layered OIT, HT, WBOIT, ...) by memory budget, over
//! several scene seeds and primitive orders, and the flicker of each under a moving camera.
//!
//! - **Budgets**: every scene is run as `oit-lab stability` runs it ([`sweep::run_scene`]:
//!   seeds x primitive orders, each image scored on the covered pixels against the A-buffer of
//!   the same stream); per budget (8, 16, 32, 64 B/px) the method of the best median PSNR and
//!   the one of the best median FLIP among those that fit ([`budget_table`]), and the verdict
//!   at 32 B/px: MLAB 4 against the best method of at most 32 B/px ([`verdict_table`]).
//! - **Camera motion** ([`camera_stream`]): a seeded path of [`CAMERA_FRAMES`] frames, a slow
//!   dolly-in with a drift: frame `t` is the scene built for a frame `t` lines taller (the
//!   scenes are laid out in units of the frame height, so it is the same scene about 0.5 %
//!   closer per frame at 180 lines), cropped to the frame size around its centre moved by a
//!   seeded drift of up to 0.4 pixels per frame. The primitives keep their submission order,
//!   as a renderer's draw calls would; what changes from frame to frame is which fragments
//!   cover a pixel and their depths. Per method and pair of consecutive frames, on the pixels
//!   covered in both: the displayed 8-bit sRGB change of the method minus that of the
//!   reference, `|(m_t+1 - m_t) - (r_t+1 - r_t)|` (largest channel), its mean in levels and the
//!   share of pixels where it exceeds 2 levels ([`Flicker`]): the flicker the method adds to
//!   what the scene itself does.

use crate::methods::catalog::{self, BUDGETS};
use crate::methods::{BinnedStream, Image, Method};
use crate::metrics::{CHANGE_LEVELS, srgb8};
use crate::out::table::{median, progress_bar, spread};
use crate::scenes::{Rng, Scene};
use crate::stream::{Frag, Stream};
use crate::study::sweep::{self, MethodRun, Plan, SceneStability};
use std::time::Instant;

/// Frames of the camera path.
pub const CAMERA_FRAMES: usize = 16;

/// Frame `frame` of the seeded camera path of `scene` at `size` (see the module).
pub fn camera_stream(scene: Scene, (w, h): (u32, u32), seed: u64, frame: usize) -> Stream {
    let mut rng = Rng::new(seed ^ 0xca3e_7a11_0000_0000 ^ (scene as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let (vx, vy) = (rng.range(-0.4, 0.4), rng.range(-0.4, 0.4));
    let ht = h + frame as u32;
    let wt = ((w as u64 * ht as u64 + h as u64 / 2) / h as u64) as u32;
    let big = scene.primitives(wt, ht, seed).stream();
    let cx = ((wt - w) as f32 / 2.0 + vx * frame as f32)
        .round()
        .clamp(0.0, (wt - w) as f32) as u32;
    let cy = ((ht - h) as f32 / 2.0 + vy * frame as f32)
        .round()
        .clamp(0.0, (ht - h) as f32) as u32;
    let frags = big
        .frags
        .iter()
        .filter_map(|f| {
            let (x, y) = (f.pixel % wt, f.pixel / wt);
            (x >= cx && x < cx + w && y >= cy && y < cy + h).then(|| Frag {
                pixel: (y - cy) * w + (x - cx),
                ..*f
            })
        })
        .collect();
    Stream {
        width: w,
        height: h,
        background: big.background,
        frags,
    }
}

/// One method's flicker over the camera path: per pair of consecutive frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Flicker {
    /// The method.
    pub method: Method,
    /// Mean over the pixels covered in both frames of `|dm - dr|` (levels, largest channel).
    pub mean: Vec<f64>,
    /// Share of those pixels where `|dm - dr|` exceeds 2 levels.
    pub share: Vec<f64>,
    /// Share of those pixels where the method's own change `|dm|` exceeds 2 levels.
    pub own: Vec<f64>,
}

/// A frame of the camera path: covered pixels and the displayed image of each method.
type Frame = (Vec<bool>, Vec<Vec<[u8; 3]>>);

fn displayed(img: &Image) -> Vec<[u8; 3]> {
    img.rgb.iter().map(|c| c.map(srgb8)).collect()
}

/// The flicker of `methods` (the first must be the A-buffer) on the camera path of `scene`.
pub fn camera_flicker(scene: Scene, size: (u32, u32), seed: u64, methods: &[Method]) -> Result<Vec<Flicker>, String> {
    let mut out: Vec<Flicker> = methods
        .iter()
        .map(|&m| Flicker {
            method: m,
            mean: Vec::new(),
            share: Vec::new(),
            own: Vec::new(),
        })
        .collect();
    // The previous frame's covered pixels and displayed images (one per method).
    let mut prev: Option<Frame> = None;
    for t in 0..CAMERA_FRAMES {
        let stream = camera_stream(scene, size, seed, t);
        stream
            .validate()
            .map_err(|(i, e)| format!("{} camera frame {t}: fragment {i}: {e}", scene.name()))?;
        let binned = BinnedStream::new(&stream);
        let covered: Vec<bool> = binned.bins.start.windows(2).map(|x| x[1] > x[0]).collect();
        let images: Vec<Vec<[u8; 3]>> = methods
            .iter()
            .map(|m| m.render(&binned).map(|img| displayed(&img)))
            .collect::<Result<_, _>>()?;
        if let Some((pc, pimg)) = &prev {
            let both: Vec<usize> = (0..covered.len()).filter(|&p| covered[p] && pc[p]).collect();
            let n = both.len().max(1) as f64;
            for (i, fl) in out.iter_mut().enumerate() {
                let (mut sum, mut over, mut own) = (0.0f64, 0usize, 0usize);
                for &p in &both {
                    let mut e = 0i32;
                    let mut d = 0i32;
                    for k in 0..3 {
                        let dm = images[i][p][k] as i32 - pimg[i][p][k] as i32;
                        let dr = images[0][p][k] as i32 - pimg[0][p][k] as i32;
                        e = e.max((dm - dr).abs());
                        d = d.max(dm.abs());
                    }
                    sum += e as f64;
                    over += usize::from(e > CHANGE_LEVELS as i32);
                    own += usize::from(d > CHANGE_LEVELS as i32);
                }
                fl.mean.push(sum / n);
                fl.share.push(over as f64 / n);
                fl.own.push(own as f64 / n);
            }
        }
        prev = Some((covered, images));
    }
    Ok(out)
}

fn run_of(sc: &SceneStability, m: Method) -> Option<&MethodRun> {
    sc.runs.iter().find(|r| r.method == m)
}

fn med_psnr(r: &MethodRun) -> f64 {
    median(&r.samples.iter().map(|s| s.psnr).collect::<Vec<_>>())
}

fn med_flip(r: &MethodRun) -> f64 {
    median(&r.samples.iter().map(|s| s.flip).collect::<Vec<_>>())
}

fn psnr_spread(r: &MethodRun) -> String {
    spread(&r.samples.iter().map(|s| s.psnr).collect::<Vec<_>>(), 1, false)
}

fn flip_spread(r: &MethodRun) -> String {
    spread(&r.samples.iter().map(|s| s.flip).collect::<Vec<_>>(), 3, false)
}

/// Four cells of a table row: the best by PSNR `(B/px)`, its PSNR spread, the best by FLIP
/// `(B/px)`, its FLIP spread.
fn best_cells(bp: &MethodRun, bf: &MethodRun) -> String {
    let cell = |r: &MethodRun, values: String| format!("{} ({:.0}) | {values}", r.method.name(), r.bytes);
    format!("{} | {}", cell(bp, psnr_spread(bp)), cell(bf, flip_spread(bf)))
}

/// The bounded methods of `sc` that fit `budget` B/px.
fn within(sc: &SceneStability, budget: usize) -> Vec<&MethodRun> {
    let bounded = catalog::bounded();
    sc.runs
        .iter()
        .filter(|r| bounded.contains(&r.method) && r.bytes <= budget as f64 + 1e-9)
        .collect()
}

/// The best of `runs` by median PSNR (highest) and by median FLIP (lowest).
fn best<'a>(runs: &[&'a MethodRun]) -> (Option<&'a MethodRun>, Option<&'a MethodRun>) {
    let by_psnr = runs.iter().copied().max_by(|a, b| med_psnr(a).total_cmp(&med_psnr(b)));
    let by_flip = runs
        .iter()
        .copied()
        .filter(|r| !med_flip(r).is_nan())
        .min_by(|a, b| med_flip(a).total_cmp(&med_flip(b)));
    (by_psnr, by_flip)
}

/// The best bounded methods that fit `budget` on `sc`: by median covered PSNR and by median
/// covered FLIP (what [`budget_table`] prints).
pub fn best_within(sc: &SceneStability, budget: usize) -> Option<(Method, Method)> {
    let runs = within(sc, budget);
    match best(&runs) {
        (Some(p), Some(f)) => Some((p.method, f.method)),
        _ => None,
    }
}

/// The largest MLAB that fits `budget`.
fn mlab_within(sc: &SceneStability, budget: usize) -> Option<&MethodRun> {
    within(sc, budget)
        .into_iter()
        .filter(|r| matches!(r.method, Method::Mlab(_)))
        .max_by(|a, b| a.bytes.total_cmp(&b.bytes))
}

/// Per scene and budget: the best method by median covered PSNR and by median covered FLIP
/// among the bounded methods that fit, and the largest MLAB that fits.
pub fn budget_table(scenes: &[SceneStability]) -> String {
    let mut s = String::from(
        "| scene | budget B/px | best by PSNR: method (B/px) | its PSNR dB median [min, max] | best by FLIP: method (B/px) | its FLIP median [min, max] | MLAB that fits | its PSNR dB / FLIP | MLAB - best: PSNR dB / FLIP |\n\
         |---|---:|---|---:|---|---:|---|---:|---:|\n",
    );
    for sc in scenes {
        for budget in BUDGETS {
            let runs = within(sc, budget);
            let (bp, bf) = best(&runs);
            let (Some(bp), Some(bf)) = (bp, bf) else { continue };
            let ml = mlab_within(sc, budget);
            let (ml_name, ml_vals, diff) = match ml {
                Some(r) => (
                    format!("{} ({:.0})", r.method.name(), r.bytes),
                    format!("{} / {}", psnr_spread(r), flip_spread(r)),
                    format!(
                        "{:+.1} / {:+.3}",
                        med_psnr(r) - med_psnr(bp),
                        med_flip(r) - med_flip(bf)
                    ),
                ),
                None => ("-".into(), "-".into(), "-".into()),
            };
            s += &format!(
                "| {} | {budget} | {} | {ml_name} | {ml_vals} | {diff} |\n",
                sc.scene.name(),
                best_cells(bp, bf),
            );
        }
    }
    s += "\nMedians [min, max] over every seed x order; covered pixels. Bounded methods only (memory that does not \
          grow with the fragments: the A-buffer and AT are not candidates). MLAB - best: the largest MLAB that fits \
          minus the best by PSNR (dB) and by FLIP (positive FLIP: MLAB worse).\n";
    s
}

/// The verdict per scene: MLAB 4 (32 B/px) against the best bounded method of at most 32 B/px
/// that is not MLAB, by median PSNR and by median FLIP, with the camera flicker of both.
pub fn verdict_table(scenes: &[SceneStability], flicker: &[(Scene, Vec<Flicker>)]) -> String {
    let mut s = String::from(
        "| scene | MLAB 4 (32 B/px): PSNR dB / FLIP | best non-MLAB <= 32 B/px by PSNR | its PSNR dB | best non-MLAB <= 32 B/px by FLIP | its FLIP | verdict | camera flicker, share of px > 2/255 beyond the reference (median [max] over frame pairs): MLAB 4 / best by PSNR / best by FLIP |\n\
         |---|---:|---|---:|---|---:|---|---:|\n",
    );
    for sc in scenes {
        let Some(m4) = run_of(sc, Method::Mlab(4)) else {
            continue;
        };
        let others: Vec<&MethodRun> = within(sc, 32)
            .into_iter()
            .filter(|r| !matches!(r.method, Method::Mlab(_)))
            .collect();
        let (Some(bp), Some(bf)) = best(&others) else { continue };
        let dp = med_psnr(m4) - med_psnr(bp);
        let df = med_flip(m4) - med_flip(bf);
        let verdict = match (dp >= 0.0, df <= 0.0) {
            (true, true) => format!("MLAB 4 wins: {dp:+.1} dB, FLIP {df:+.3}"),
            (false, false) => format!("MLAB 4 loses: {dp:+.1} dB, FLIP {df:+.3}"),
            _ => format!("mixed: {dp:+.1} dB, FLIP {df:+.3}"),
        };
        let fl = |m: Method| {
            flicker
                .iter()
                .find(|(x, _)| *x == sc.scene)
                .and_then(|(_, v)| v.iter().find(|f| f.method == m))
                .map_or("-".to_string(), |f| {
                    let mx = f.share.iter().copied().fold(0.0f64, f64::max);
                    format!("{:.1} % [{:.1} %]", 100.0 * median(&f.share), 100.0 * mx)
                })
        };
        s += &format!(
            "| {} | {} / {} | {} | {verdict} | {} / {} / {} |\n",
            sc.scene.name(),
            psnr_spread(m4),
            flip_spread(m4),
            best_cells(bp, bf),
            fl(Method::Mlab(4)),
            fl(bp.method),
            fl(bf.method),
        );
    }
    s += "\nWins: MLAB 4's median PSNR at least the best other's and its median FLIP at most the best other's; \
          loses: both worse; mixed otherwise. The differences are MLAB 4 minus the best other (dB; FLIP, negative: \
          MLAB better). '-' in the flicker column: the method is not in the camera run.\n";
    s
}

/// The camera-motion table: per scene and method, the flicker beyond the reference's.
pub fn flicker_table(flicker: &[(Scene, Vec<Flicker>)]) -> String {
    let mut s = String::from(
        "| scene | method | mean excess change (levels): median [max] over frame pairs | px with excess > 2/255: median [max] | px changing > 2/255 (own change): median |\n\
         |---|---|---:|---:|---:|\n",
    );
    for (scene, v) in flicker {
        for f in v {
            let mx = |x: &[f64]| x.iter().copied().fold(0.0f64, f64::max);
            s += &format!(
                "| {} | {} | {:.3} [{:.3}] | {:.1} % [{:.1} %] | {:.1} % |\n",
                scene.name(),
                f.method.name(),
                median(&f.mean),
                mx(&f.mean),
                100.0 * median(&f.share),
                100.0 * mx(&f.share),
                100.0 * median(&f.own),
            );
        }
    }
    s += &format!(
        "\n{CAMERA_FRAMES} frames per scene ({} pairs), scene seed 1; excess change: `|(m_t+1 - m_t) - (r_t+1 - r_t)|` \
         in displayed 8-bit sRGB levels (largest channel) on the pixels covered in both frames, r the A-buffer \
         (whose own row is 0 by construction; its own-change column is the scene's).\n",
        CAMERA_FRAMES - 1
    );
    s
}

/// What a peers run does.
#[derive(Clone, Debug)]
pub struct PeersPlan {
    /// Frame size.
    pub size: (u32, u32),
    /// Scene seeds.
    pub seeds: Vec<u64>,
    /// Primitive orders per seed.
    pub orders: usize,
    /// Compute FLIP.
    pub with_flip: bool,
    /// Run the camera path.
    pub camera: bool,
}

/// `oit-lab peers`: the budget tables, the verdicts and the camera flicker; prints Markdown.
pub fn command(plan: &PeersPlan, scenes: &[Scene]) -> Result<(), String> {
    let start = Instant::now();
    let all = catalog::peers();
    let splan = Plan {
        size: plan.size,
        seeds: plan.seeds.clone(),
        orders: plan.orders,
        methods: all.clone(),
        with_flip: plan.with_flip,
        pair_flip: Vec::new(),
        strip: None,
    };
    let pb = progress_bar((scenes.len() * (plan.seeds.len() * plan.orders + usize::from(plan.camera))) as u64);
    let mut results = Vec::new();
    let mut flicker = Vec::new();
    for &sc in scenes {
        let r = sweep::run_scene(sc, &splan, |seed, o| {
            pb.set_message(format!("{} seed {seed} order {o}", sc.name()));
            pb.inc(1);
        })?;
        results.push(r);
        if plan.camera {
            pb.set_message(format!("{} camera path", sc.name()));
            flicker.push((sc, camera_flicker(sc, plan.size, plan.seeds[0], &catalog::flicker())?));
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    println!(
        "# oit-lab peers: {}x{}, seeds {:?}, {} orders each, {} scenes x {} methods{}, {:.0} s\n",
        plan.size.0,
        plan.size.1,
        plan.seeds,
        plan.orders,
        scenes.len(),
        all.len(),
        if plan.camera {
            format!(", camera path of {CAMERA_FRAMES} frames (seed {})", plan.seeds[0])
        } else {
            String::new()
        },
        start.elapsed().as_secs_f64()
    );
    println!("## Best method by memory budget\n\n{}", budget_table(&results));
    println!(
        "## MLAB 4 against the best other method at <= 32 B/px\n\n{}",
        verdict_table(&results, &flicker)
    );
    if plan.camera {
        println!(
            "## Camera motion: flicker beyond the reference's\n\n{}",
            flicker_table(&flicker)
        );
    }
    println!(
        "## Every method (covered PSNR and FLIP over seeds and orders)\n\n{}",
        sweep::table(&results, &all)
    );
    Ok(())
}
