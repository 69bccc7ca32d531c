//! Seeds x primitive orders, the engine of `oit-lab stability` (issue 10) and `oit-lab peers`
//! (issue 25): how much each method's image depends on the order in which the same primitives
//! are submitted, and how its quality spreads over orders and scene seeds ([`run_scene`]), and
//! the table of both commands ([`table`]).
//!
//! Every scene is built from each seed, then submitted in several primitive orders: order 0 is
//! the scene's own order (HAIR strand by strand root to tip, FOREST tree by tree, ...), orders
//! 1, 2, ... are seeded Fisher-Yates shuffles of the primitive list ([`order`]). Each order is
//! rasterized to a fragment stream and every method composites it; each image is scored
//! against the A-buffer of the same order on the covered pixels, and compared with the same
//! method's image of the previous order ([`Change`]: share of covered pixels whose displayed
//! 8-bit sRGB value moves by more than 2 levels, mean FLIP between the two). Per pixel, the
//! spread of the displayed values over all orders is kept too.
//!
//! HT is order independent by construction (its head keeps the nearest K fragments, its tail
//! sums are integers), and so is MLAB when it has at least as many rows as a pixel has
//! fragments (no merge happens): both come out with zero change (tests/stability.rs).

use crate::methods::depth::{Depth, depth};
use crate::methods::{BinnedStream, Image, Method};
use crate::metrics::{Change, Scorer, change, srgb8};
use crate::out::table::{HT_NOTE, median, min_med_max};
use crate::par;
use crate::scenes::{Primitives, Rng, Scene};

/// The primitives of `prims` in submission order number `order`: order 0 is the list as
/// built, any other order a Fisher-Yates shuffle seeded from the scene seed and the order.
pub fn order(prims: &Primitives, seed: u64, order: usize) -> Primitives {
    let mut p = prims.clone();
    if order > 0 {
        let mut rng = Rng::new(
            seed.wrapping_mul(0xd1b5_4a32_d192_ed03) ^ (order as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5851_f42d,
        );
        rng.shuffle(&mut p.prims);
    }
    p
}

/// What a run does.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Frame size.
    pub size: (u32, u32),
    /// Scene seeds.
    pub seeds: Vec<u64>,
    /// Number of orders per seed (order 0 and `orders - 1` shuffles).
    pub orders: usize,
    /// Methods (see [`crate::methods::catalog::stability`]); `Method::Reference` may be among them.
    pub methods: Vec<Method>,
    /// Compute FLIP (against the reference and between orders).
    pub with_flip: bool,
    /// The methods whose change between orders gets a FLIP too (FLIP is the costly part of a
    /// run; the others get the 8-bit change only).
    pub pair_flip: Vec<Method>,
    /// The method of the strip image, and how many orders it shows (of the first seed).
    pub strip: Option<(Method, usize)>,
}

/// One image's scores against the reference of the same order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Scene seed.
    pub seed: u64,
    /// Order number.
    pub order: usize,
    /// PSNR over covered pixels, dB.
    pub psnr: f64,
    /// Whole-image PSNR, dB.
    pub psnr_whole: f64,
    /// Mean FLIP over covered pixels (NaN when not computed).
    pub flip: f64,
    /// Mean SSIM over covered pixels.
    pub ssim: f64,
}

/// One method over every seed and order.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodRun {
    /// The method.
    pub method: Method,
    /// Bytes per pixel.
    pub bytes: f64,
    /// One sample per seed and order.
    pub samples: Vec<Sample>,
    /// The change between consecutive orders (order `i` against `i + 1`) of each seed.
    pub pairs: Vec<Change>,
    /// Per seed: share of the covered pixels whose displayed 8-bit value (any channel) spreads
    /// by more than 2 levels over all the seed's orders.
    pub spread_share: Vec<f64>,
    /// Largest spread of a displayed 8-bit channel over one seed's orders, in levels.
    pub spread_max: u8,
    /// Every order of every seed gave the same image, bit for bit.
    pub identical: bool,
}

/// The strip image's data: the method's images of the first orders of the first seed, and the
/// per-pixel spread (8-bit levels, largest channel) over all orders of that seed.
#[derive(Clone, Debug)]
pub struct Strip {
    /// The method.
    pub method: Method,
    /// `(order, image)`.
    pub images: Vec<(usize, Image)>,
    /// Spread in levels per pixel.
    pub spread: Vec<u8>,
    /// Covered pixels.
    pub covered: Vec<bool>,
    /// Number of orders the spread is over.
    pub orders: usize,
}

/// A scene over every seed and order.
#[derive(Clone, Debug)]
pub struct SceneStability {
    /// The scene.
    pub scene: Scene,
    /// Fragments per covered pixel, per seed.
    pub depth: Vec<Depth>,
    /// Fragments per seed.
    pub fragments: Vec<usize>,
    /// One entry per method of the plan, in order.
    pub runs: Vec<MethodRun>,
    /// The strip, when asked.
    pub strip: Option<Strip>,
}

/// Per method and seed: the previous order's image, and the running min and max of the
/// displayed 8-bit values per pixel and channel.
struct Track {
    prev: Option<Image>,
    lo: Vec<[u8; 3]>,
    hi: Vec<[u8; 3]>,
}

impl Track {
    fn new(pixels: usize) -> Track {
        Track {
            prev: None,
            lo: vec![[255; 3]; pixels],
            hi: vec![[0; 3]; pixels],
        }
    }

    /// Per pixel, the spread of the displayed 8-bit values over the orders seen (levels,
    /// largest channel).
    fn levels(&self) -> Vec<u8> {
        (0..self.lo.len())
            .map(|p| {
                (0..3)
                    .map(|k| self.hi[p][k].saturating_sub(self.lo[p][k]))
                    .max()
                    .unwrap_or(0)
            })
            .collect()
    }
}

impl MethodRun {
    fn new(method: Method) -> MethodRun {
        MethodRun {
            method,
            bytes: 0.0,
            samples: Vec::new(),
            pairs: Vec::new(),
            spread_share: Vec::new(),
            spread_max: 0,
            identical: true,
        }
    }
}

/// One seed of a scene: its fragments per covered pixel and fragments (order 0), and the
/// strip when this seed makes it.
struct SeedRun {
    depth: Depth,
    fragments: usize,
    strip: Option<Strip>,
}

/// Run `plan` on `scene`. `progress` is called after each order with `(seed, order)`.
pub fn run_scene(scene: Scene, plan: &Plan, mut progress: impl FnMut(u64, usize)) -> Result<SceneStability, String> {
    let mut runs: Vec<MethodRun> = plan.methods.iter().map(|&m| MethodRun::new(m)).collect();
    let (mut depths, mut fragments, mut strip) = (Vec::new(), Vec::new(), None);
    for (si, &seed) in plan.seeds.iter().enumerate() {
        let r = run_seed(scene, plan, seed, si == 0, &mut runs, &mut progress)?;
        depths.push(r.depth);
        fragments.push(r.fragments);
        if r.strip.is_some() {
            strip = r.strip;
        }
    }
    Ok(SceneStability {
        scene,
        depth: depths,
        fragments,
        runs,
        strip,
    })
}

/// Every order of one seed: render and score ([`render_order`]), compare with the previous
/// order and fold into the tracks ([`fold_order`]), then each method's spread over the orders.
/// `first` is the first seed (the one of the strip).
fn run_seed(
    scene: Scene,
    plan: &Plan,
    seed: u64,
    first: bool,
    runs: &mut [MethodRun],
    progress: &mut impl FnMut(u64, usize),
) -> Result<SeedRun, String> {
    let (w, h) = plan.size;
    let n = w as usize * h as usize;
    let built = scene.primitives(w, h, seed);
    let mut tracks: Vec<Track> = plan.methods.iter().map(|_| Track::new(n)).collect();
    let (mut covered, mut depth0, mut fragments) = (Vec::new(), None, 0);
    let mut strip_images = Vec::new();
    let strip_method = plan.strip.filter(|_| first);
    for o in 0..plan.orders.max(1) {
        let stream = order(&built, seed, o).stream();
        stream
            .validate()
            .map_err(|(i, e)| format!("{} seed {seed} order {o}: fragment {i}: {e}", scene.name()))?;
        let binned = BinnedStream::new(&stream);
        if o == 0 {
            covered = binned.bins.start.windows(2).map(|x| x[1] > x[0]).collect();
            depth0 = Some(depth(&binned));
            fragments = stream.frags.len();
        }
        let images = render_order(plan, &binned, &covered, seed, o, runs)?;
        let keep = strip_method.filter(|&(_, count)| o < count).map(|(m, _)| m);
        for img in fold_order(plan, &covered, images, &mut tracks, runs, keep)? {
            strip_images.push((o, img));
        }
        progress(seed, o);
    }
    let mut strip = None;
    for (i, t) in tracks.iter().enumerate() {
        let levels = t.levels();
        let (mut cov, mut moved) = (0usize, 0usize);
        for p in (0..n).filter(|&p| covered[p]) {
            cov += 1;
            moved += usize::from(levels[p] > crate::metrics::CHANGE_LEVELS);
            runs[i].spread_max = runs[i].spread_max.max(levels[p]);
        }
        runs[i]
            .spread_share
            .push(if cov > 0 { moved as f64 / cov as f64 } else { 0.0 });
        if let Some((m, _)) = strip_method
            && m == plan.methods[i]
        {
            strip = Some(Strip {
                method: m,
                images: std::mem::take(&mut strip_images),
                spread: levels,
                covered: covered.clone(),
                orders: plan.orders.max(1),
            });
        }
    }
    Ok(SeedRun {
        depth: depth0.ok_or("no order rendered")?,
        fragments,
        strip,
    })
}

/// Render and score every method of `plan` in order `o`, on all cores (the kernel methods are
/// single threaded); each method's sample and bytes go to its run.
fn render_order(
    plan: &Plan,
    binned: &BinnedStream,
    covered: &[bool],
    seed: u64,
    o: usize,
    runs: &mut [MethodRun],
) -> Result<Vec<Image>, String> {
    let reference = Method::Reference.render(binned)?;
    let scorer = Scorer::new(&reference, covered);
    let results = par::map(plan.methods.len(), |i| {
        let m = plan.methods[i];
        let img = if m == Method::Reference {
            reference.clone()
        } else {
            m.render(binned)?
        };
        let q = scorer.score(&img, plan.with_flip);
        let sample = Sample {
            seed,
            order: o,
            psnr: q.covered.psnr,
            psnr_whole: q.whole.psnr,
            flip: q.flip_covered.unwrap_or(f64::NAN),
            ssim: q.ssim_covered,
        };
        Ok::<_, String>((img, sample))
    })?;
    let mut images = Vec::with_capacity(results.len());
    for (i, r) in results.into_iter().enumerate() {
        let (img, sample) = r?;
        runs[i].samples.push(sample);
        runs[i].bytes = plan.methods[i].bytes_per_pixel(binned);
        images.push(img);
    }
    Ok(images)
}

/// Compare each method's image with its previous order's (on all cores, FLIP per pair for the
/// methods of `plan.pair_flip`) and fold it into the method's track: the change, whether it is
/// bit-identical, the per-pixel range of the displayed values. Returns a copy of the images of
/// the method `keep` (the strip's).
fn fold_order(
    plan: &Plan,
    covered: &[bool],
    images: Vec<Image>,
    tracks: &mut [Track],
    runs: &mut [MethodRun],
    keep: Option<Method>,
) -> Result<Vec<Image>, String> {
    let changes = par::map(images.len(), |i| {
        tracks[i].prev.as_ref().map(|prev| {
            let flip = plan.with_flip && plan.pair_flip.contains(&plan.methods[i]);
            change(prev, &images[i], covered, flip)
        })
    })?;
    let mut out = Vec::new();
    for (i, img) in images.into_iter().enumerate() {
        let t = &mut tracks[i];
        if let Some(c) = changes[i] {
            runs[i].pairs.push(c);
        }
        if let Some(prev) = &t.prev {
            runs[i].identical &= *prev == img;
        }
        for ((px, lo), hi) in img.rgb.iter().zip(t.lo.iter_mut()).zip(t.hi.iter_mut()) {
            for ((&c, l), h) in px.iter().zip(lo.iter_mut()).zip(hi.iter_mut()) {
                let v = srgb8(c);
                *l = (*l).min(v);
                *h = (*h).max(v);
            }
        }
        if keep == Some(plan.methods[i]) {
            out.push(img.clone());
        }
        t.prev = Some(img);
    }
    Ok(out)
}

/// Per seed, the range (max - min) of the covered PSNR over the seed's orders; infinite
/// values (an exact image) count as the largest finite one plus nothing: a seed whose orders
/// are all exact has range 0, one mixing exact and inexact images has an infinite range.
fn order_ranges(run: &MethodRun) -> Vec<f64> {
    let mut seeds: Vec<u64> = run.samples.iter().map(|s| s.seed).collect();
    seeds.dedup();
    seeds
        .iter()
        .map(|&seed| {
            let v: Vec<f64> = run.samples.iter().filter(|s| s.seed == seed).map(|s| s.psnr).collect();
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo == hi { 0.0 } else { hi - lo }
        })
        .collect()
}

/// Median of the covered PSNR of order 0 (the scene's own order) and of the shuffled orders,
/// over every seed: how much MLAB draws on the coherence of the scene's own order.
pub fn own_vs_shuffled(run: &MethodRun) -> (f64, f64) {
    let own: Vec<f64> = run.samples.iter().filter(|s| s.order == 0).map(|s| s.psnr).collect();
    let shuffled: Vec<f64> = run.samples.iter().filter(|s| s.order > 0).map(|s| s.psnr).collect();
    (median(&own), median(&shuffled))
}

/// The stability table: per scene and method (those of `shown`), covered PSNR and FLIP min /
/// median / max over every seed and order, the median over seeds of the PSNR range over
/// orders, the change between consecutive orders, and the per-pixel spread over all orders.
pub fn table(scenes: &[SceneStability], shown: &[Method]) -> String {
    let mut s = String::from(
        "| scene | method | B/px | PSNR covered dB: min / median / max | PSNR range over orders dB (median [max] over seeds) | own order / shuffled: median PSNR dB | FLIP covered: min / median / max | between consecutive orders: FLIP covered, median [max] | px changing > 2/255 between consecutive orders: median [max] | px spreading > 2/255 over all orders (median over seeds) | largest spread (levels) | bit-identical over orders |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|\n",
    );
    for sc in scenes {
        for run in sc.runs.iter().filter(|r| shown.contains(&r.method)) {
            let psnr: Vec<f64> = run.samples.iter().map(|x| x.psnr).collect();
            let flip: Vec<f64> = run.samples.iter().map(|x| x.flip).collect();
            let ranges = order_ranges(run);
            let pair_flip: Vec<f64> = run.pairs.iter().map(|c| c.flip.unwrap_or(f64::NAN)).collect();
            let pair_share: Vec<f64> = run.pairs.iter().map(|c| 100.0 * c.share).collect();
            let (own, shuf) = own_vs_shuffled(run);
            let max = |v: &[f64]| v.iter().copied().filter(|x| !x.is_nan()).fold(f64::NAN, f64::max);
            let num = |x: f64, d: usize| {
                if x.is_nan() {
                    "-".to_string()
                } else if x.is_infinite() {
                    "inf".to_string()
                } else {
                    format!("{x:.d$}")
                }
            };
            s += &format!(
                "| {} | {} | {:.0} | {} | {} [{}] | {} / {} | {} | {} [{}] | {} % [{} %] | {} % | {} | {} |\n",
                sc.scene.name(),
                run.method.name(),
                run.bytes,
                min_med_max(&psnr, 1),
                num(median(&ranges), 1),
                num(max(&ranges), 1),
                num(own, 1),
                num(shuf, 1),
                min_med_max(&flip, 3),
                num(median(&pair_flip), 4),
                num(max(&pair_flip), 4),
                num(median(&pair_share), 1),
                num(max(&pair_share), 1),
                num(100.0 * median(&run.spread_share), 1),
                run.spread_max,
                if run.identical { "yes" } else { "no" }
            );
        }
    }
    s += &format!(
        "\nSamples: every seed x order; covered: pixels with at least one fragment; a pixel \
         changes when a displayed 8-bit sRGB channel moves by more than 2 levels. {}\n",
        HT_NOTE
    );
    s
}
