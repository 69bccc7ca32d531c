//! The evaluation of one stream: the reference, every method, their metrics and timings,
//! and the Markdown tables.

use crate::methods::{Frame, Image, Method};
use crate::metrics::{Quality, compare};
use crate::stream::Stream;
use std::time::Instant;

/// One method's result on one stream.
pub struct Entry {
    /// The method.
    pub method: Method,
    /// Its image.
    pub image: Image,
    /// Metrics against the reference.
    pub quality: Quality,
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
    let frame = Frame::new(stream);
    let t = Instant::now();
    let image = Method::Reference.render(&frame)?;
    let ms = (t.elapsed().as_secs_f64() + frame.sort_seconds) * 1e3;
    let quality = compare(&image, &image, false);
    let reference = Entry {
        method: Method::Reference,
        bytes: Method::Reference.bytes_per_pixel(&frame),
        image,
        quality,
        ms,
    };
    tick("A-buffer");
    // Render one method at a time (each uses every core, so the timings are comparable),
    // then compute the metrics of all of them on all cores.
    let mut rendered = Vec::with_capacity(methods.len());
    for &m in methods {
        let t = Instant::now();
        let image = m.render(&frame)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        rendered.push((m, image, ms));
        tick(&m.name());
    }
    let queue = std::sync::Mutex::new((0..rendered.len()).rev().collect::<Vec<_>>());
    let results = std::sync::Mutex::new(vec![None; rendered.len()]);
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).clamp(1, 16);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                while let Some(i) = queue.lock().ok().and_then(|mut q| q.pop()) {
                    let q = compare(&reference.image, &rendered[i].1, with_flip);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(q);
                    }
                }
            });
        }
    });
    let results = results.into_inner().map_err(|_| "metrics thread failed".to_string())?;
    let mut entries = Vec::with_capacity(methods.len());
    for ((m, image, ms), q) in rendered.into_iter().zip(results) {
        let quality = q.ok_or("metrics thread failed")?;
        entries.push(Entry {
            method: m,
            bytes: m.bytes_per_pixel(&frame),
            image,
            quality,
            ms,
        });
    }
    Ok(Evaluation {
        name: name.to_string(),
        fragments: stream.frags.len(),
        max_depth: frame.bins.max_depth_complexity(),
        counts: frame.bins.start.windows(2).map(|w| w[1] - w[0]).collect(),
        reference,
        entries,
    })
}

fn num(x: f64, digits: usize) -> String {
    if x.is_infinite() {
        "inf".into()
    } else {
        format!("{x:.digits$}")
    }
}

/// The full Markdown table: one row per scene and method.
pub fn full_table(evals: &[Evaluation]) -> String {
    let mut s = String::from(
        "| scene | method | B/px | ms | RMSE | PSNR dB | max err | mean FLIP | signed err | vis bias |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for e in evals {
        let r = &e.reference;
        s += &format!(
            "| {} | {} ({} frags, max {}/px) | {:.1} | {:.1} | 0 | inf | 0 | 0 | 0 | 0 |\n",
            e.name,
            r.method.name(),
            e.fragments,
            e.max_depth,
            r.bytes,
            r.ms
        );
        for x in &e.entries {
            let q = &x.quality;
            s += &format!(
                "| {} | {} | {:.0} | {:.1} | {:.4} | {} | {:.3} | {} | {:+.4} | {:+.4} |\n",
                e.name,
                x.method.name(),
                x.bytes,
                x.ms,
                q.rmse,
                num(q.psnr, 1),
                q.max_abs,
                q.flip.map_or("-".into(), |f| format!("{f:.4}")),
                q.mean_signed,
                q.vis_bias
            );
        }
    }
    s
}

/// The summary: one row per method, PSNR / mean FLIP per scene.
pub fn summary_table(evals: &[Evaluation]) -> String {
    let Some(first) = evals.first() else {
        return String::new();
    };
    let mut s = String::from("| method | B/px |");
    for e in evals {
        s += &format!(" {} PSNR / FLIP |", e.name);
    }
    s += "\n|---|---:|";
    s += &"---:|".repeat(evals.len());
    s += "\n";
    for (i, x) in first.entries.iter().enumerate() {
        s += &format!("| {} | {:.0} |", x.method.name(), x.bytes);
        for e in evals {
            match e.entries.get(i) {
                Some(y) => {
                    let f = y.quality.flip.map_or("-".into(), |f| format!("{f:.3}"));
                    s += &format!(" {} / {} |", num(y.quality.psnr, 1), f);
                }
                None => s += " - |",
            }
        }
        s += "\n";
    }
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
