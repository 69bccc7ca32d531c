//! The tables and the scaling plot of `oit-lab bench`, from the measures of a run.

use super::timing::{Measure, What};
use crate::tiled::{TileSize, TiledMethod, storage_bytes};

/// MLAB 4 against tile size (from the measures of [`super::run`] with several tile sizes).
pub fn band_table(all: &[Measure]) -> String {
    let mut rows: Vec<&Measure> = all
        .iter()
        .filter(|m| m.what == What::Frame(TiledMethod::Mlab4))
        .collect();
    rows.sort_by_key(|m| (m.scene as usize, m.threads, m.tile.lines, m.tile.width));
    let mut s = String::from(
        "| scene | threads | tile (columns x lines; 0: whole lines) | ms (median) | spread | CPU ms | ns / fragment | CPU ns / fragment | peak RSS MiB |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for m in rows {
        s += &format!(
            "| {} | {} | {} | {:.2} | {:.0}% | {:.2} | {:.2} | {:.2} | {:.1} |\n",
            m.scene.name(),
            m.threads,
            m.tile,
            m.timing.median * 1e3,
            m.timing.spread_percent(),
            m.timing.cpu * 1e3,
            m.ns_per_fragment(),
            m.cpu_ns_per_fragment(),
            mib(m.peak_rss)
        );
    }
    s
}

fn mib(b: u64) -> f64 {
    b as f64 / 1048576.0
}

/// The tables of a bench run (markdown) of a `width`-wide frame: the frame timings, the
/// processes with only the primitives, the scaling and the storage per frame.
pub fn tables(all: &[Measure], width: u32) -> String {
    let mut s = String::new();
    s += "## Frame timings (median, spread = (max - min) / median; memory = peak RSS of the child process)\n\n";
    s += "| scene | method | threads | ms (median) | min - max ms | spread | CPU ms | CPU / wall | ns / fragment | CPU ns / fragment | peak RSS MiB | accounted MiB | RSS / accounted | frame path MiB (RSS - idle) | / accounted - primitives | bytes / pixel (RSS) | time / MLAB 4 | CPU / MLAB 4 | CPU / replay |\n";
    s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for m in all.iter().filter(|m| m.what != What::Idle) {
        s += &frame_row(all, m);
    }
    for m in all.iter().filter(|m| m.what == What::Idle) {
        s += &format!(
            "\nProcess with only {}'s primitives ({:.2} MiB of them): peak RSS {:.1} MiB.",
            m.scene.name(),
            mib(m.prims),
            mib(m.peak_rss)
        );
    }
    s += "\n\n## Scaling (speedup and parallel efficiency over 1 thread)\n\n| scene | method | threads | speedup | efficiency |\n|---|---|---:|---:|---:|\n";
    for m in all.iter().filter(|m| m.threads > 1) {
        if let Some(one) = all
            .iter()
            .find(|x| x.scene == m.scene && x.what == m.what && x.threads == 1 && x.tile == m.tile)
        {
            let sp = one.timing.median / m.timing.median;
            s += &format!(
                "| {} | {} | {} | {:.2} | {:.0}% |\n",
                m.scene.name(),
                m.what.name(),
                m.threads,
                sp,
                100.0 * sp / m.threads as f64
            );
        }
    }
    s += &storage_table(all, width);
    s
}

/// One row of the frame timings table: `m` with its ratios to MLAB 4 and the replay of the
/// same run, and its memory against what the frame path holds by design.
fn frame_row(all: &[Measure], m: &Measure) -> String {
    let find = |what: What, threads: usize| {
        all.iter()
            .find(|x| x.scene == m.scene && x.what == what && x.threads == threads && x.tile == m.tile)
    };
    let ratio = |x: Option<&Measure>| {
        x.map_or("-".to_string(), |x| {
            format!("{:.2}x", m.timing.median / x.timing.median)
        })
    };
    let cpu_ratio = |x: Option<&Measure>| x.map_or("-".to_string(), |x| format!("{:.2}x", m.timing.cpu / x.timing.cpu));
    // Per fragment, one thread against the one-thread replay, in CPU time.
    let per_replay = |x: Option<&Measure>| match x {
        Some(x) if m.threads == 1 => format!("{:.2}x", m.cpu_ns_per_fragment() / x.cpu_ns_per_fragment()),
        _ => "-".to_string(),
    };
    let (acc, rel) = match m.what {
        What::Frame(_) => (
            format!("{:.1}", mib(m.accounted())),
            format!("{:.2}", m.peak_rss as f64 / m.accounted() as f64),
        ),
        _ => ("-".into(), "-".into()),
    };
    // The frame path's own memory: the peak above the process that only built the
    // primitives (both measured), against what it holds by design without them.
    let idle = all.iter().find(|x| x.scene == m.scene && x.what == What::Idle);
    let (own, own_rel) = match (m.what, idle) {
        (What::Frame(_), Some(i)) => {
            let own = m.peak_rss.saturating_sub(i.peak_rss);
            let acc = m.accounted().saturating_sub(m.prims);
            (
                format!("{:.1}", mib(own)),
                format!("{:.2}", own as f64 / acc.max(1) as f64),
            )
        }
        _ => ("-".into(), "-".into()),
    };
    format!(
        "| {} ({:.1} M frags) | {} | {} | {:.2} | {:.2} - {:.2} | {:.0}% | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} | {acc} | {rel} | {own} | {own_rel} | {:.1} | {} | {} | {} |\n",
        m.scene.name(),
        m.fragments as f64 / 1e6,
        m.what.name(),
        m.threads,
        m.timing.median * 1e3,
        m.timing.min * 1e3,
        m.timing.max * 1e3,
        m.timing.spread_percent(),
        m.timing.cpu * 1e3,
        m.timing.cpu_per_wall,
        m.ns_per_fragment(),
        m.cpu_ns_per_fragment(),
        mib(m.peak_rss),
        m.peak_rss as f64 / m.pixels as f64,
        ratio(find(What::Frame(TiledMethod::Mlab4), m.threads)),
        cpu_ratio(find(What::Frame(TiledMethod::Mlab4), m.threads)),
        per_replay(find(What::Replay, 1)),
    )
}

/// The storage per frame ([`storage_bytes`]): each method's whole-frame target and its tiled
/// one, and the A-buffer on each scene.
fn storage_table(all: &[Measure], width: u32) -> String {
    let mut s = String::new();
    let px = all.first().map_or(0, |m| m.pixels);
    s += &format!(
        "\n## Storage per frame ([`storage_bytes`]: target + RGBA8 output), {px} pixels\n\n| method | bytes / pixel |\n|---|---:|\n"
    );
    let tile = all.first().map_or_else(TileSize::default, |m| m.tile);
    let columns = if tile.width == 0 { width } else { tile.width.min(width) };
    let tile_px = columns.next_multiple_of(8) as usize * tile.lines as usize;
    for method in [TiledMethod::Mlab4, TiledMethod::Wboit, TiledMethod::Over] {
        // The tiled renderer holds one tile's target per worker, not the frame's.
        let per_worker = storage_bytes(method, tile_px, 0) - 4 * tile_px;
        s += &format!(
            "| {0}, a whole-frame target | {1} |\n| {0}, tiled: one {2}x{5} tile's target per worker ({3} B) + output | {4:.2} per worker + 4 |\n",
            method.name(),
            storage_bytes(method, 1, 0),
            columns.next_multiple_of(8),
            per_worker,
            per_worker as f64 / px.max(1) as f64,
            tile.lines
        );
    }
    for m in all
        .iter()
        .filter(|m| m.what == What::Frame(TiledMethod::ABuffer) && m.threads == 1)
    {
        let whole = storage_bytes(TiledMethod::ABuffer, m.pixels, m.fragments as usize);
        s += &format!(
            "| A-buffer on {}, whole frame as Table 1 counts it (12 B x {} fragments + heads) | {:.1} |\n| A-buffer on {}, tiled: the largest tile's {} fragments | {:.1} |\n",
            m.scene.name(),
            m.fragments,
            whole as f64 / m.pixels as f64,
            m.scene.name(),
            m.band_fragments,
            storage_bytes(TiledMethod::ABuffer, m.pixels, m.band_fragments as usize) as f64 / m.pixels as f64
        );
    }
    s
}

/// The scaling plot: speedup over one thread against threads, one line per scene and
/// method, and the ideal line. Small hand-written SVG.
pub fn scaling_svg(results: &[Measure], title: &str) -> String {
    let threads_max = results.iter().map(|m| m.threads).max().unwrap_or(1).max(2);
    let plot = Plot::new(threads_max);
    let (left, top, pw) = (plot.left, plot.top, plot.pw);
    let mut svg = plot.axes(title);
    let mut series: Vec<(String, String)> = Vec::new();
    for m in results {
        let key = (m.scene.name().to_string(), m.what.name().to_string());
        if !series.contains(&key)
            && results
                .iter()
                .filter(|x| (x.scene.name(), x.what.name()) == (key.0.as_str(), key.1.as_str()))
                .count()
                > 1
        {
            series.push(key);
        }
    }
    for (i, (scene, what)) in series.iter().enumerate() {
        svg += &plot.series(results, i, scene, what);
    }
    svg += &format!(
        "<text x=\"{}\" y=\"{}\" fill=\"#777\">dashed grey: ideal</text>\n</svg>\n",
        left + pw + 10.0,
        top + 12.0 + 16.0 * series.len() as f64 + 4.0
    );
    svg
}

/// The series' colors, in turn.
const COLORS: [&str; 8] = [
    "#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
];

/// The plot area of [`scaling_svg`]: threads on x (1 to `threads_max`), speedup on y (0 to
/// `threads_max`).
struct Plot {
    threads_max: usize,
    w: f64,
    h: f64,
    left: f64,
    top: f64,
    pw: f64,
    ph: f64,
}

impl Plot {
    fn new(threads_max: usize) -> Plot {
        let (w, h, left, bottom, top, right) = (560.0, 340.0, 50.0, 40.0, 30.0, 190.0);
        Plot {
            threads_max,
            w,
            h,
            left,
            top,
            pw: w - left - right,
            ph: h - top - bottom,
        }
    }

    fn sx(&self, t: f64) -> f64 {
        self.left + (t - 1.0) / (self.threads_max as f64 - 1.0) * self.pw
    }

    fn sy(&self, s: f64) -> f64 {
        self.top + self.ph - (s / self.threads_max as f64) * self.ph
    }

    /// The header, the axes with their ticks and labels, and the ideal line.
    fn axes(&self, title: &str) -> String {
        let Plot {
            threads_max,
            w,
            h,
            left,
            top,
            pw,
            ph,
        } = *self;
        let sx = |t: f64| self.sx(t);
        let sy = |s: f64| self.sy(s);
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
        svg
    }

    /// One series: its speedups over its one-thread run as a polyline, and its legend entry
    /// (the `i`-th).
    fn series(&self, results: &[Measure], i: usize, scene: &str, what: &str) -> String {
        let Plot { left, top, pw, .. } = *self;
        let sx = |t: f64| self.sx(t);
        let sy = |s: f64| self.sy(s);
        let mut svg = String::new();
        let pts: Vec<&Measure> = results
            .iter()
            .filter(|m| m.scene.name() == scene && m.what.name() == what)
            .collect();
        let Some(one) = pts.iter().find(|m| m.threads == 1) else {
            return svg;
        };
        let color = COLORS[i % COLORS.len()];
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

        svg
    }
}
