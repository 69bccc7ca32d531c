//! The evaluation of one stream: the reference, every method, their metrics and timings,
//! and the Markdown tables (the engine of `oit-lab run` and `oit-lab evaluate`, [`super::run`]).

use crate::methods::depth::{Depth, depth};
use crate::methods::{BinnedStream, Image, Method};
use crate::metrics::{Scorer, Scores, score};
use crate::out::table::{COVERED_NOTE, HT_NOTE, num};
use crate::par;
use crate::stream::Stream;
use std::time::Instant;

/// One method's result on one stream.
pub struct Entry {
    /// The method.
    pub method: Method,
    /// Its image.
    pub image: Image,
    /// Metrics against the reference (whole image and covered pixels).
    pub scores: Scores,
    /// Memory per pixel in bytes.
    pub bytes: f64,
    /// Milliseconds to composite the frame (the A-buffer's includes its sort).
    pub ms: f64,
}

/// Everything measured on one stream.
pub struct Evaluation {
    /// Scene or file name.
    pub name: String,
    /// Number of fragments.
    pub fragments: usize,
    /// Largest fragment count of a pixel.
    pub max_depth: usize,
    /// Fragment count per pixel.
    pub counts: Vec<u32>,
    /// Fragments per covered pixel (mean, max).
    pub depth: Depth,
    /// Covered pixels (the reference has at least one fragment there).
    pub covered: Vec<bool>,
    /// The reference entry (metrics against itself: all zero).
    pub reference: Entry,
    /// The methods, in the order asked.
    pub entries: Vec<Entry>,
}

/// Render `stream` with the reference and `methods`, compare each with the reference.
/// `tick` is called after each rendered image (for a progress bar).
pub fn evaluate(
    name: &str,
    stream: &Stream,
    methods: &[Method],
    with_flip: bool,
    mut tick: impl FnMut(&str),
) -> Result<Evaluation, String> {
    stream
        .validate()
        .map_err(|(i, e)| format!("{name}: fragment {i}: {e}"))?;
    let binned = BinnedStream::new(stream);
    let t = Instant::now();
    let image = Method::Reference.render(&binned)?;
    let ms = (t.elapsed().as_secs_f64() + binned.sort_seconds) * 1e3;
    let covered: Vec<bool> = binned.bins.start.windows(2).map(|w| w[1] > w[0]).collect();
    let scores = score(&image, &image, &covered, false);
    let reference = Entry {
        method: Method::Reference,
        bytes: Method::Reference.bytes_per_pixel(&binned),
        image,
        scores,
        ms,
    };
    tick("A-buffer");
    // Render one method at a time (each uses every core, so the timings are comparable),
    // then compute the metrics of all of them on all cores.
    let mut rendered = Vec::with_capacity(methods.len());
    for &m in methods {
        let t = Instant::now();
        let image = m.render(&binned)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        rendered.push((m, image, ms));
        tick(&m.name());
    }
    let scorer = Scorer::new(&reference.image, &covered);
    let results = par::map(rendered.len(), |i| scorer.score(&rendered[i].1, with_flip))?;
    let mut entries = Vec::with_capacity(methods.len());
    for ((m, image, ms), scores) in rendered.into_iter().zip(results) {
        entries.push(Entry {
            method: m,
            bytes: m.bytes_per_pixel(&binned),
            image,
            scores,
            ms,
        });
    }
    Ok(Evaluation {
        name: name.to_string(),
        fragments: stream.frags.len(),
        max_depth: binned.bins.max_depth_complexity(),
        counts: binned.bins.start.windows(2).map(|w| w[1] - w[0]).collect(),
        depth: depth(&binned),
        covered,
        reference,
        entries,
    })
}

/// The full Markdown table: one row per scene and method, covered-pixel metrics beside the
/// whole-image ones, then the notes ([`COVERED_NOTE`], [`HT_NOTE`]).
pub fn full_table(evals: &[Evaluation]) -> String {
    let mut s = String::from(
        "| scene | method | B/px | ms | PSNR covered dB | PSNR whole dB | FLIP covered | FLIP whole | SSIM covered | SSIM whole | max err | signed err | vis bias mean (covered) | vis bias max (covered) |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for e in evals {
        let r = &e.reference;
        s += &format!(
            "| {} | {} ({} frags, {:.1} per covered px, max {}) | {:.1} | {:.1} | inf | inf | 0 | 0 | 1 | 1 | 0 | 0 | 0 | 0 |\n",
            e.name,
            r.method.name(),
            e.fragments,
            e.depth.mean,
            e.max_depth,
            r.bytes,
            r.ms
        );
        for x in &e.entries {
            let q = &x.scores;
            let f = |v: Option<f64>| v.map_or("-".into(), |f| format!("{f:.4}"));
            s += &format!(
                "| {} | {} | {:.0} | {:.1} | {} | {} | {} | {} | {:.4} | {:.4} | {:.3} | {:+.4} | {:+.4} | {:+.4} |\n",
                e.name,
                x.method.name(),
                x.bytes,
                x.ms,
                num(q.covered.psnr, 1),
                num(q.whole.psnr, 1),
                f(q.flip_covered),
                f(q.whole.flip),
                q.ssim_covered,
                q.ssim,
                q.whole.max_abs,
                q.whole.mean_signed,
                q.covered.vis_bias,
                q.covered.vis_worst
            );
        }
    }
    s += &format!(
        "\n{COVERED_NOTE} vis bias: method minus exact background visibility, mean and the pixel of largest magnitude (signed). {HT_NOTE}\n"
    );
    s
}

/// The summary: one row per method, PSNR on covered pixels / mean FLIP on covered pixels
/// per scene, then the notes.
pub fn summary_table(evals: &[Evaluation]) -> String {
    let Some(first) = evals.first() else {
        return String::new();
    };
    let mut s = String::from("| method | B/px |");
    for e in evals {
        s += &format!(" {} PSNR / FLIP (covered) |", e.name);
    }
    s += "\n|---|---:|";
    s += &"---:|".repeat(evals.len());
    s += "\n";
    for (i, x) in first.entries.iter().enumerate() {
        s += &format!("| {} | {:.0} |", x.method.name(), x.bytes);
        for e in evals {
            match e.entries.get(i) {
                Some(y) => {
                    let f = y.scores.flip_covered.map_or("-".into(), |f| format!("{f:.3}"));
                    s += &format!(" {} / {} |", num(y.scores.covered.psnr, 1), f);
                }
                None => s += " - |",
            }
        }
        s += "\n";
    }
    s += &format!("\n{COVERED_NOTE} {HT_NOTE}\n");
    s
}

/// Mean signed error of background visibility over the pixels with at least `min_frags`
/// fragments, per method: `(method name, bias, pixels)`.
pub fn vis_bias_where(e: &Evaluation, min_frags: u32) -> Vec<(String, f64, usize)> {
    let sel: Vec<usize> = (0..e.counts.len()).filter(|&p| e.counts[p] >= min_frags).collect();
    e.entries
        .iter()
        .map(|x| {
            let s: f64 = sel
                .iter()
                .map(|&p| x.image.vis[p] as f64 - e.reference.image.vis[p] as f64)
                .sum();
            (x.method.name(), s / sel.len().max(1) as f64, sel.len())
        })
        .collect()
}
