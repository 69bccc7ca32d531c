//! `oit-lab bench`: frame-level timings of [`crate::frame`] with warm-up, repetitions,
//! median and spread, thread scaling, and the scaling plot (SVG).

use crate::frame::{Compositor, FrameMethod};
use crate::stream::Stream;
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Untimed runs before measuring.
    pub warmup: usize,
    /// Timed runs; the median is reported.
    pub reps: usize,
    /// Thread counts (each a `rayon` pool of that size).
    pub threads: Vec<usize>,
    /// Lines per band.
    pub band_lines: u32,
}

/// Median and spread of repeated timings, in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Median.
    pub median: f64,
    /// Fastest.
    pub min: f64,
    /// Slowest.
    pub max: f64,
    /// CPU time of the process over wall time of the timed runs (Linux; NaN elsewhere): about
    /// the thread count when the machine was ours, less when other work shared the cores.
    pub cpu_per_wall: f64,
}

impl Timing {
    /// From samples (at least one).
    pub fn of(mut samples: Vec<f64>) -> Timing {
        samples.sort_by(f64::total_cmp);
        let n = samples.len();
        let median = if n == 0 {
            f64::NAN
        } else if n % 2 == 1 {
            samples[n / 2]
        } else {
            (samples[n / 2 - 1] + samples[n / 2]) / 2.0
        };
        Timing {
            cpu_per_wall: f64::NAN,
            median,
            min: samples.first().copied().unwrap_or(f64::NAN),
            max: samples.last().copied().unwrap_or(f64::NAN),
        }
    }

    /// `(max - min) / median`, in percent.
    pub fn spread_percent(&self) -> f64 {
        100.0 * (self.max - self.min) / self.median
    }
}

/// Time `f` `warmup + reps` times, keep the last `reps`.
pub fn time<F: FnMut() -> Result<(), String>>(warmup: usize, reps: usize, mut f: F) -> Result<Timing, String> {
    for _ in 0..warmup {
        f()?;
    }
    let mut samples = Vec::with_capacity(reps);
    let cpu0 = process_cpu_seconds();
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        f()?;
        samples.push(t.elapsed().as_secs_f64());
    }
    let wall: f64 = samples.iter().sum();
    let cpu = process_cpu_seconds() - cpu0;
    Ok(Timing {
        cpu_per_wall: cpu / wall,
        ..Timing::of(samples)
    })
}

/// User + system CPU seconds of this process (`/proc/self/stat`, 100 ticks per second),
/// NaN where unavailable.
pub fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name (which is in parentheses and may hold spaces).
    let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name.
    match (
        f.get(11).and_then(|x| x.parse::<f64>().ok()),
        f.get(12).and_then(|x| x.parse::<f64>().ok()),
    ) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

/// A `rayon` pool of `threads` threads.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())
}

/// One measurement.
#[derive(Clone, Debug)]
pub struct Measure {
    /// Scene name.
    pub scene: String,
    /// Method or phase name.
    pub what: String,
    /// Threads.
    pub threads: usize,
    /// Fragments in the frame.
    pub fragments: usize,
    /// The timing.
    pub timing: Timing,
}

impl Measure {
    /// Nanoseconds per fragment (median).
    pub fn ns_per_fragment(&self) -> f64 {
        self.timing.median * 1e9 / self.fragments.max(1) as f64
    }
}

/// Every frame method at every thread count, plus (one thread) MLAB's binning alone and
/// MLAB without bins (whole frame, stream order).
pub fn run(scene: &str, stream: &Stream, plan: &Plan, mut log: impl FnMut(&Measure)) -> Result<Vec<Measure>, String> {
    let mut out = vec![[0u8; 4]; stream.pixels()];
    let mut results = Vec::new();
    let mut push = |what: &str, threads: usize, timing: Timing, results: &mut Vec<Measure>| {
        let m = Measure {
            scene: scene.into(),
            what: what.into(),
            threads,
            fragments: stream.frags.len(),
            timing,
        };
        log(&m);
        results.push(m);
    };
    for &t in &plan.threads {
        let pool = pool(t)?;
        let mut c = Compositor::new(plan.band_lines);
        for m in FrameMethod::ALL {
            let timing = pool.install(|| time(plan.warmup, plan.reps, || c.render(m, stream, &mut out)))?;
            push(m.name(), t, timing, &mut results);
        }
        if t == 1 {
            let timing = pool.install(|| time(plan.warmup, plan.reps, || c.bin_rows(stream)))?;
            push("MLAB 4: binning alone", t, timing, &mut results);
            let mut storage = Vec::new();
            let timing = time(plan.warmup, plan.reps, || {
                crate::frame::mlab_unbinned::<4>(stream, &mut storage, &mut out)
            })?;
            push("MLAB 4 lanes, no bins", t, timing, &mut results);
        }
    }
    Ok(results)
}

/// MLAB 4 at every band height in `lines`, `threads` threads.
pub fn bands(stream: &Stream, plan: &Plan, lines: &[u32], threads: usize) -> Result<Vec<(u32, Timing)>, String> {
    let pool = pool(threads)?;
    let mut out = vec![[0u8; 4]; stream.pixels()];
    lines
        .iter()
        .map(|&l| {
            let mut c = Compositor::new(l);
            let t = pool.install(|| {
                time(plan.warmup, plan.reps, || {
                    c.render(FrameMethod::Mlab4, stream, &mut out)
                })
            })?;
            Ok((l, t))
        })
        .collect()
}

/// The scaling plot: speedup over one thread against threads, one line per scene and
/// method, and the ideal line. Small hand-written SVG.
pub fn scaling_svg(results: &[Measure], title: &str) -> String {
    let threads_max = results.iter().map(|m| m.threads).max().unwrap_or(1).max(2);
    let (w, h, left, bottom, top, right) = (560.0, 340.0, 50.0, 40.0, 30.0, 190.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let ymax = threads_max as f64;
    let sx = |t: f64| left + (t - 1.0) / (threads_max as f64 - 1.0) * pw;
    let sy = |s: f64| top + ph - (s / ymax) * ph;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">\n\
         <rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
         <text x=\"{left}\" y=\"18\" font-size=\"13\">{title}</text>\n"
    );
    // Axes and ticks.
    svg += &format!(
        "<line x1=\"{left}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n<line x1=\"{left}\" y1=\"{top}\" x2=\"{left}\" y2=\"{}\" stroke=\"black\"/>\n",
        top + ph,
        left + pw,
        top + ph,
        top + ph
    );
    let mut t = 1;
    while t <= threads_max {
        svg += &format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{t}</text>\n",
            sx(t as f64),
            top + ph + 15.0
        );
        t *= 2;
    }
    for s in 0..=threads_max {
        if threads_max <= 4 || s % 2 == 0 {
            svg += &format!(
                "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{s}</text>\n",
                left - 5.0,
                sy(s as f64) + 4.0
            );
        }
    }
    svg += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">threads</text>\n<text x=\"12\" y=\"{}\" transform=\"rotate(-90 12 {})\" text-anchor=\"middle\">speedup over 1 thread</text>\n",
        left + pw / 2.0,
        h - 6.0,
        top + ph / 2.0,
        top + ph / 2.0
    );
    svg += &format!(
        "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#999\" stroke-dasharray=\"4 3\"/>\n",
        sx(1.0),
        sy(1.0),
        sx(threads_max as f64),
        sy(threads_max as f64)
    );
    let colors = [
        "#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    ];
    let mut series: Vec<(String, String)> = Vec::new();
    for m in results {
        let key = (m.scene.clone(), m.what.clone());
        if !series.contains(&key)
            && results
                .iter()
                .filter(|x| (&x.scene, &x.what) == (&key.0, &key.1))
                .count()
                > 1
        {
            series.push(key);
        }
    }
    for (i, (scene, what)) in series.iter().enumerate() {
        let pts: Vec<&Measure> = results
            .iter()
            .filter(|m| &m.scene == scene && &m.what == what)
            .collect();
        let Some(one) = pts.iter().find(|m| m.threads == 1) else {
            continue;
        };
        let color = colors[i % colors.len()];
        let dash = if i % 2 == 1 { " stroke-dasharray=\"6 2\"" } else { "" };
        let path: Vec<String> = pts
            .iter()
            .map(|m| {
                let s = one.timing.median / m.timing.median;
                format!("{:.1},{:.1}", sx(m.threads as f64), sy(s))
            })
            .collect();
        svg += &format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"2\"{dash}/>\n",
            path.join(" ")
        );
        let ly = top + 12.0 + 16.0 * i as f64;
        svg += &format!(
            "<line x1=\"{}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{color}\" stroke-width=\"2\"{dash}/><text x=\"{}\" y=\"{}\">{scene} {what}</text>\n",
            left + pw + 10.0,
            left + pw + 30.0,
            left + pw + 35.0,
            ly + 4.0
        );
    }
    svg += &format!(
        "<text x=\"{}\" y=\"{}\" fill=\"#777\">dashed grey: ideal</text>\n</svg>\n",
        left + pw + 10.0,
        top + 12.0 + 16.0 * series.len() as f64 + 4.0
    );
    svg
}
