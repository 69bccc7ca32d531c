//! Issue 9: many faint or dense layers. What the HT tail has to hold (the sums over each
//! pixel's fragments beyond the nearest `K`), fragments per covered pixel, and the report of
//! `oit-lab faint` (MLAB and HT at equal memory, both arithmetics, against unsorted OVER).

use crate::methods::Frame;

/// Fragments per covered pixel (a pixel is covered when it has at least one fragment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Depth {
    /// Pixels with at least one fragment.
    pub covered: usize,
    /// Mean fragment count over the covered pixels (0 when none is covered).
    pub mean: f64,
    /// Largest fragment count of a pixel.
    pub max: usize,
}

/// Fragments per covered pixel of a frame.
pub fn depth(frame: &Frame) -> Depth {
    let (mut covered, mut total, mut max) = (0usize, 0usize, 0usize);
    for w in frame.bins.start.windows(2) {
        let n = (w[1] - w[0]) as usize;
        if n > 0 {
            covered += 1;
            total += n;
            max = max.max(n);
        }
    }
    Depth {
        covered,
        mean: if covered > 0 {
            total as f64 / covered as f64
        } else {
            0.0
        },
        max,
    }
}

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
/// the kernel quantizes it; rows that carry neither color nor opacity are not counted, as
/// the kernel's tail skips them. Errors for a fragment the kernel refuses.
pub fn tail_sums(frame: &Frame, k: usize) -> Result<Vec<TailSums>, String> {
    let frags = &frame.stream.frags;
    let mut out = vec![TailSums::default(); frame.stream.pixels()];
    for (p, sums) in out.iter_mut().enumerate() {
        for &i in frame.sorted.of(p).iter().skip(k) {
            let row = frags[i as usize]
                .to_kernel()
                .map_err(|e| format!("fragment {i}: {e}"))?
                .row();
            if row.is_invisible() {
                continue;
            }
            let [r, g, b, t] = row.rgbt();
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

/// Tail-sum statistics of a frame with `k` head rows.
pub fn tail_stats(frame: &Frame, k: usize) -> Result<TailStats, String> {
    let sums = tail_sums(frame, k)?;
    let covered: Vec<usize> = (0..sums.len()).filter(|&p| !frame.bins.of(p).is_empty()).collect();
    let get = |t: &TailSums, i: usize| if i < 3 { t.color[i] } else if i == 3 { t.alpha } else { t.count };
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
        depth: depth(frame),
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
    s
}
