//! Issue 9: many faint or dense layers. What the HT tail has to hold (the sums over each
//! pixel's fragments beyond the nearest `K`), fragments per covered pixel, and the report of
//! `oit-lab faint` (MLAB and HT at equal memory, both arithmetics, against unsorted OVER).

use crate::methods::depth::{Depth, depth};
use crate::methods::{Arith, BinnedStream, Image, Method, catalog, hybrid_with, quantize};
use crate::metrics::{Covered, Quality, compare, compare_covered};
use crate::out::table::{HT_NOTE, header, spread};
use crate::par;
use crate::scenes::Scene;
use crate::stream::Stream;
use std::time::Instant;

/// Exact (unsaturated) tail sums of one pixel, in units of 1/255: the sums HT's tail would
/// hold with fields wide enough never to saturate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TailSums {
    /// Sums of the premultiplied color bytes `[R, G, B]`.
    pub color: [u64; 3],
    /// Sum of the alpha bytes (`255 - T`).
    pub alpha: u64,
    /// Number of fragments accumulated.
    pub count: u64,
}

/// Per pixel, the sums over the fragments beyond the nearest `k` (front to back, a later
/// submission in front on equal depth, as HT's head keeps them), each quantized to a row as
/// the kernel quantizes it in arithmetic `arith`; rows that carry neither color nor opacity
/// are not counted, as the kernel's tail skips them. Errors for a fragment the kernel refuses.
pub fn tail_sums(binned: &BinnedStream, k: usize, arith: Arith) -> Result<Vec<TailSums>, String> {
    let frags = &binned.stream.frags;
    let mut out = vec![TailSums::default(); binned.stream.pixels()];
    for (p, sums) in out.iter_mut().enumerate() {
        for &i in binned.sorted.of(p).iter().skip(k) {
            let fragment = frags[i as usize]
                .to_kernel()
                .map_err(|e| format!("fragment {i}: {e}"))?;
            #[expect(clippy::cast_possible_truncation, reason = "pixel indices of a lab frame fit in u32")]
            let row = quantize(arith, &fragment, p as u32);
            if row.is_invisible() {
                continue;
            }
            let ([r, g, b], t) = (row.color(), row.transmittance());
            sums.color[0] += r as u64;
            sums.color[1] += g as u64;
            sums.color[2] += b as u64;
            sums.alpha += 255 - t as u64;
            sums.count += 1;
        }
    }
    Ok(out)
}

/// The `q`-quantile (nearest rank, `q` in `[0, 1]`) of `values`; 0 for none.
pub fn quantile(values: &mut [u64], q: f64) -> u64 {
    if values.is_empty() {
        return 0;
    }
    values.sort_unstable();
    let q = if q.is_nan() { 1.0 } else { q.clamp(0.0, 1.0) };
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

/// One scene's tail-sum statistics over its covered pixels (see [`tail_sums`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TailStats {
    /// Fragments per covered pixel.
    pub depth: Depth,
    /// Per field (`R`, `G`, `B`, alpha, count): the 99th percentile, the 99.9th percentile and
    /// the maximum over covered pixels, in units of 1/255 (count: fragments).
    pub fields: [[u64; 3]; 5],
    /// Covered pixels where a field of the paper's tail would be at its maximum, that is
    /// saturated (a color sum of 1023 or more, or an alpha sum or count of 65535 or more).
    pub paper_saturated: usize,
}

/// Names of [`TailStats::fields`].
pub const TAIL_FIELDS: [&str; 5] = ["R", "G", "B", "alpha", "count"];

/// Tail-sum statistics of a frame with `k` head rows, fragments quantized in `arith`.
pub fn tail_stats(binned: &BinnedStream, k: usize, arith: Arith) -> Result<TailStats, String> {
    let sums = tail_sums(binned, k, arith)?;
    let covered: Vec<usize> = (0..sums.len()).filter(|&p| !binned.bins.of(p).is_empty()).collect();
    let get = |t: &TailSums, i: usize| {
        if i < 3 {
            t.color[i]
        } else if i == 3 {
            t.alpha
        } else {
            t.count
        }
    };
    let fields = std::array::from_fn(|i| {
        let mut v: Vec<u64> = covered.iter().map(|&p| get(&sums[p], i)).collect();
        [quantile(&mut v, 0.99), quantile(&mut v, 0.999), quantile(&mut v, 1.0)]
    });
    let paper_saturated = covered
        .iter()
        .filter(|&&p| {
            let t = &sums[p];
            t.color.iter().any(|&c| c >= 1023) || t.alpha >= 65535 || t.count >= 65535
        })
        .count();
    Ok(TailStats {
        depth: depth(binned),
        fields,
        paper_saturated,
    })
}

/// The Markdown table of [`tail_stats`]: one row per `(scene name, seed, stats)`.
pub fn tail_table(rows: &[(String, u64, TailStats)], k: usize) -> String {
    let mut s = format!(
        "| scene | seed | frags / covered px (mean, max) | {} | paper tail saturated |\n|---|---:|---:|",
        TAIL_FIELDS
            .map(|f| format!("{f} beyond K = {k}: p99 / p99.9 / max"))
            .join(" | ")
    );
    s += &"---:|".repeat(TAIL_FIELDS.len() + 1);
    s += "\n";
    for (name, seed, t) in rows {
        s += &format!("| {name} | {seed} | {:.1}, {} |", t.depth.mean, t.depth.max);
        for [a, b, c] in t.fields {
            s += &format!(" {a} / {b} / {c} |");
        }
        let pct = 100.0 * t.paper_saturated as f64 / t.depth.covered.max(1) as f64;
        s += &format!(" {} px ({pct:.1} %) |\n", t.paper_saturated);
    }
    s += &format!("\n{}\n", HT_NOTE);
    s
}

/// One method on one stream.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    /// The method.
    pub method: Method,
    /// Memory per pixel in bytes.
    pub bytes: f64,
    /// Whole-image metrics (PSNR over every pixel; mean FLIP of the whole image).
    pub quality: Quality,
    /// Metrics over the covered pixels.
    pub covered: Covered,
    /// HT only: pixels whose tail has a field at its maximum.
    pub saturated: Option<usize>,
}

/// Every method of a report on one scene and seed.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRun {
    /// The scene.
    pub scene: Scene,
    /// Its seed.
    pub seed: u64,
    /// Number of fragments.
    pub fragments: usize,
    /// Fragments per covered pixel.
    pub depth: Depth,
    /// One entry per method, in the order asked.
    pub measures: Vec<Measure>,
}

/// Render `stream` with the reference and `methods` (on all cores: the kernel methods run
/// single-threaded, so methods run side by side) and measure each against the reference.
pub fn run_stream(
    scene: Scene,
    seed: u64,
    stream: &Stream,
    methods: &[Method],
    with_flip: bool,
) -> Result<SceneRun, String> {
    stream
        .validate()
        .map_err(|(i, e)| format!("{}: fragment {i}: {e}", scene.name()))?;
    let binned = BinnedStream::new(stream);
    let reference = Method::Reference.render(&binned)?;
    let covered: Vec<bool> = binned.bins.start.windows(2).map(|w| w[1] > w[0]).collect();
    let measures = par::map(methods.len(), |i| {
        measure(&binned, &reference, &covered, methods[i], with_flip)
    })?
    .into_iter()
    .collect::<Result<Vec<_>, _>>()?;
    Ok(SceneRun {
        scene,
        seed,
        fragments: stream.frags.len(),
        depth: depth(&binned),
        measures,
    })
}

fn measure(
    binned: &BinnedStream,
    reference: &Image,
    covered: &[bool],
    m: Method,
    with_flip: bool,
) -> Result<Measure, String> {
    let (image, saturated) = match m {
        Method::HybridWith(k, a) => hybrid_with(k, a, binned).map(|(i, s)| (i, Some(s)))?,
        _ => (m.render(binned)?, None),
    };
    Ok(Measure {
        method: m,
        bytes: m.bytes_per_pixel(binned),
        quality: compare(reference, &image, with_flip),
        covered: compare_covered(reference, &image, covered),
        saturated,
    })
}

/// The value of largest magnitude (0 for none).
fn worst(values: impl IntoIterator<Item = f64>) -> f64 {
    values
        .into_iter()
        .fold(0.0, |w, x| if x.abs() > f64::abs(w) { x } else { w })
}

/// Runs of one scene over several seeds, each with the same methods in the same order.
fn by_scene(runs: &[SceneRun]) -> Vec<(Scene, Vec<&SceneRun>)> {
    let mut out: Vec<(Scene, Vec<&SceneRun>)> = Vec::new();
    for r in runs {
        match out.iter_mut().find(|(s, _)| *s == r.scene) {
            Some((_, v)) => v.push(r),
            None => out.push((r.scene, vec![r])),
        }
    }
    out
}

fn scene_label(runs: &[&SceneRun]) -> String {
    let means: Vec<f64> = runs.iter().map(|r| r.depth.mean).collect();
    let max = runs.iter().map(|r| r.depth.max).max().unwrap_or(0);
    format!(
        "{} ({} per covered px, max {max})",
        runs.first().map_or("?", |r| r.scene.name()),
        spread(&means, 1, false)
    )
}

/// The full table: per scene (fragments per covered pixel: mean over seeds as median [min,
/// max], and the largest count), per method: PSNR on covered pixels, whole-image PSNR, mean
/// FLIP, visibility bias (mean over covered pixels; worst pixel over every seed; mean of its
/// magnitude), the
/// error's high-frequency part ([`Covered::noise`]), saturated HT tails (pixels, share of
/// the covered pixels).
pub fn full_table(runs: &[SceneRun]) -> String {
    let mut s = String::from(
        "| scene | method | B/px | PSNR covered dB | PSNR dB | mean FLIP | vis bias mean | vis bias worst | vis abs err | noise | saturated tails |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for (_, rs) in by_scene(runs) {
        let label = scene_label(&rs);
        let Some(first) = rs.first() else { continue };
        for (i, m) in first.measures.iter().enumerate() {
            let col = |f: &dyn Fn(&Measure) -> f64| -> Vec<f64> {
                rs.iter().filter_map(|r| r.measures.get(i)).map(f).collect()
            };
            let sat = match m.saturated {
                Some(_) => {
                    let px = col(&|x| x.saturated.unwrap_or(0) as f64);
                    let pct = col(&|x| 100.0 * x.saturated.unwrap_or(0) as f64 / x.covered.pixels.max(1) as f64);
                    format!("{} px ({} %)", spread(&px, 0, false), spread(&pct, 1, false))
                }
                None => "-".into(),
            };
            s += &format!(
                "| {label} | {} | {:.0} | {} | {} | {} | {} | {:+.4} | {} | {} | {sat} |\n",
                m.method.name(),
                m.bytes,
                spread(&col(&|x| x.covered.psnr), 1, false),
                spread(&col(&|x| x.quality.psnr), 1, false),
                spread(&col(&|x| x.quality.flip.unwrap_or(f64::NAN)), 3, false),
                spread(&col(&|x| x.covered.vis_bias), 4, true),
                worst(col(&|x| x.covered.vis_worst)),
                spread(&col(&|x| x.covered.vis_abs), 4, false),
                spread(&col(&|x| x.covered.noise), 4, false),
            );
        }
    }
    s += &format!("\n{}\n", HT_NOTE);
    s
}

/// The headline: per scene, PSNR on covered pixels and mean FLIP (median [min, max] over
/// seeds) of unsorted OVER, MLAB 4 and HT 3 (32 B/px), each arithmetic.
pub fn headline_table(runs: &[SceneRun]) -> String {
    let cols: Vec<Method> = std::iter::once(Method::Over)
        .chain(Arith::ALL.map(|a| Method::MlabWith(4, a)))
        .chain(Arith::ALL.map(|a| Method::HybridWith(3, a)))
        .collect();
    let mut s = String::from("| scene | frags / covered px (mean; max) |");
    for m in &cols {
        s += &format!(" {} |", m.name());
    }
    s += "\n|---|---:|";
    s += &"---:|".repeat(cols.len());
    s += "\n";
    for (scene, rs) in by_scene(runs) {
        let means: Vec<f64> = rs.iter().map(|r| r.depth.mean).collect();
        let max = rs.iter().map(|r| r.depth.max).max().unwrap_or(0);
        s += &format!("| {} | {}; {max} |", scene.name(), spread(&means, 1, false));
        for m in &cols {
            let pick = |f: &dyn Fn(&Measure) -> f64| -> Vec<f64> {
                rs.iter()
                    .filter_map(|r| r.measures.iter().find(|x| x.method == *m))
                    .map(f)
                    .collect()
            };
            let psnr = pick(&|x| x.covered.psnr);
            if psnr.is_empty() {
                s += " - |";
                continue;
            }
            s += &format!(
                " {} dB / {} |",
                spread(&psnr, 1, false),
                spread(&pick(&|x| x.quality.flip.unwrap_or(f64::NAN)), 3, false)
            );
        }
        s += "\n";
    }
    s += &format!("\n{}\n", HT_NOTE);
    s
}

/// `oit-lab faint --tails`: no rendering, the HT tail sums with `k` head rows, fragments
/// quantized in `arith` ([`tail_stats`]), per scene and seed.
pub fn tails_command(size: (u32, u32), seeds: &[u64], scenes: &[Scene], k: usize, arith: Arith) -> Result<(), String> {
    let start = Instant::now();
    let mut rows = Vec::new();
    for sc in scenes {
        for &seed in seeds {
            let stream = sc.generate(size.0, size.1, seed);
            stream
                .validate()
                .map_err(|(i, e)| format!("{}: fragment {i}: {e}", sc.name()))?;
            let binned = BinnedStream::new(&stream);
            rows.push((sc.name().to_string(), seed, tail_stats(&binned, k, arith)?));
        }
    }
    println!(
        "# oit-lab faint --tails: {}x{}, seeds {seeds:?}, K = {k}, {} quantization, {:.1} s\n",
        size.0,
        size.1,
        arith.name(),
        start.elapsed().as_secs_f64()
    );
    println!("{}", tail_table(&rows, k));
    Ok(())
}

/// `oit-lab faint`: every scene of `scenes` at every seed of `seeds` with [`catalog::faint`]
/// ([`run_stream`]); prints the headline table and every method's.
pub fn command(size: (u32, u32), seeds: &[u64], scenes: &[Scene], with_flip: bool) -> Result<(), String> {
    let start = Instant::now();
    let methods = catalog::faint();
    let mut runs = Vec::new();
    for sc in scenes {
        for &seed in seeds {
            let t = Instant::now();
            let stream = sc.generate(size.0, size.1, seed);
            let r = run_stream(*sc, seed, &stream, &methods, with_flip)?;
            eprintln!(
                "{} seed {seed}: {} fragments, {:.1} s",
                sc.name(),
                stream.frags.len(),
                t.elapsed().as_secs_f64()
            );
            runs.push(r);
        }
    }
    let counts = (scenes.len(), methods.len());
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{}",
        header("oit-lab faint", size, &format!("seeds {seeds:?}"), counts, secs)
    );
    println!(
        "Values are median [min, max] over the seeds; covered pixels are those where the reference \
         has at least one fragment; `paper` and `unbiased` are the kernel's arithmetics \
         (`mlab::Paper`, `mlab::Unbiased`, the default).\n"
    );
    println!(
        "## PSNR on covered pixels / mean FLIP, 32 B/px against OVER\n\n{}",
        headline_table(&runs)
    );
    println!("## Every method\n\n{}", full_table(&runs));
    Ok(())
}
