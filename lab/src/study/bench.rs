//! `oit-lab bench`: frame-level timings of [`crate::tiled`] with warm-up, repetitions,
//! median and spread, thread scaling, peak resident memory, the kernel-only replay bound,
//! the tables and the scaling plot (SVG).
//!
//! Each configuration (scene, method, threads) runs in a child process (`oit-lab bench
//! --one ...`, [`measure`]) so that its peak resident memory (`VmHWM` of
//! `/proc/self/status`) is its own: the child builds the primitives, renders warm-up and
//! timed frames, and prints one [`Measure`] line that the parent parses.

use crate::scenes::Scene;
use crate::tiled::{PrimBins, TileSize, TiledMethod, TiledRenderer, raster_only, replay_mlab4, storage_bytes};
use std::path::Path;
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
    /// Tile size (lines per band, columns per tile).
    pub tile: TileSize,
    /// Frame size.
    pub size: (u32, u32),
    /// Scene seed.
    pub seed: u64,
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
    /// Median CPU seconds per run, all threads of the process (Linux `schedstat`, ns
    /// resolution; NaN elsewhere): what the work cost when other work shared the cores.
    pub cpu: f64,
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
            cpu: f64::NAN,
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
    let mut cpus = Vec::with_capacity(reps);
    for _ in 0..reps.max(1) {
        let c = threads_cpu_seconds();
        let t = Instant::now();
        f()?;
        samples.push(t.elapsed().as_secs_f64());
        cpus.push(threads_cpu_seconds() - c);
    }
    let wall: f64 = samples.iter().sum();
    let cpu: f64 = cpus.iter().sum();
    Ok(Timing {
        cpu_per_wall: cpu / wall,
        cpu: Timing::of(cpus).median,
        ..Timing::of(samples)
    })
}

/// CPU seconds run by all threads of this process so far: the sum of the first field of
/// `/proc/self/task/*/schedstat` (nanoseconds); NaN where unavailable.
pub fn threads_cpu_seconds() -> f64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    let mut ns = 0u64;
    for e in dir.flatten() {
        let Ok(s) = std::fs::read_to_string(e.path().join("schedstat")) else {
            return f64::NAN;
        };
        match s.split_whitespace().next().and_then(|v| v.parse::<u64>().ok()) {
            Some(v) => ns += v,
            None => return f64::NAN,
        }
    }
    ns as f64 * 1e-9
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

/// What one configuration times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum What {
    /// A whole frame with a method of the tiled renderer.
    Frame(TiledMethod),
    /// The kernel-only replay of MLAB 4's span inserts ([`replay_mlab4`], one thread).
    Replay,
    /// The rasterizer alone ([`raster_only`], one thread).
    Raster,
    /// Nothing but the primitives: the process's own footprint.
    Idle,
}

impl What {
    /// Short name for the command line.
    pub fn key(self) -> &'static str {
        match self {
            What::Frame(m) => m.key(),
            What::Replay => "replay",
            What::Raster => "raster",
            What::Idle => "idle",
        }
    }

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            What::Frame(m) => m.name(),
            What::Replay => "MLAB 4 kernel-only replay",
            What::Raster => "rasterizer alone",
            What::Idle => "process + primitives only",
        }
    }

    /// From a short name.
    pub fn from_key(s: &str) -> Option<What> {
        match s {
            "replay" => Some(What::Replay),
            "raster" => Some(What::Raster),
            "idle" => Some(What::Idle),
            _ => TiledMethod::from_key(s).map(What::Frame),
        }
    }
}

/// One measured configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    /// Scene.
    pub scene: Scene,
    /// What was timed.
    pub what: What,
    /// Threads.
    pub threads: usize,
    /// Tile size.
    pub tile: TileSize,
    /// Pixels in the frame.
    pub pixels: usize,
    /// Fragments in the frame.
    pub fragments: u64,
    /// The timing.
    pub timing: Timing,
    /// Peak resident memory of the process that measured (`VmHWM`), bytes.
    pub peak_rss: u64,
    /// Bytes of the targets and bins held by the renderer (as allocated).
    pub held: u64,
    /// Bytes of the primitive list.
    pub prims: u64,
    /// The most fragments one tile of the A-buffer held (0 for other methods).
    pub band_fragments: u64,
}

impl Measure {
    /// Nanoseconds per fragment (median wall time).
    pub fn ns_per_fragment(&self) -> f64 {
        self.timing.median * 1e9 / self.fragments.max(1) as f64
    }

    /// CPU nanoseconds per fragment (median CPU time, all threads).
    pub fn cpu_ns_per_fragment(&self) -> f64 {
        self.timing.cpu * 1e9 / self.fragments.max(1) as f64
    }

    /// Framebuffer or target + output + primitive bins + primitives, as allocated (the
    /// capacities of [`TiledRenderer::held_bytes`] and [`Primitives::bytes`](crate::scenes::Primitives::bytes)):
    /// what the frame path holds, the figure the measured peak resident memory
    /// ([`peak_rss`]) is compared with. The method's storage by formula is
    /// [`storage_bytes`] ([`Method::storage`](crate::methods::Method::storage)).
    pub fn accounted(&self) -> u64 {
        self.held + 4 * self.pixels as u64 + self.prims
    }

    /// The child's output line.
    pub fn to_line(&self) -> String {
        let t = &self.timing;
        format!(
            "MEASURE {} {} {} {} {} {} {:e} {:e} {:e} {:e} {:e} {} {} {} {}",
            self.scene.name(),
            self.what.key(),
            self.threads,
            self.tile,
            self.pixels,
            self.fragments,
            t.median,
            t.min,
            t.max,
            t.cpu_per_wall,
            t.cpu,
            self.peak_rss,
            self.held,
            self.prims,
            self.band_fragments
        )
    }

    /// Parse a [`to_line`](Self::to_line) line.
    pub fn from_line(line: &str) -> Option<Measure> {
        let f: Vec<&str> = line.strip_prefix("MEASURE ")?.split_whitespace().collect();
        if f.len() != 15 {
            return None;
        }
        let num = |i: usize| f[i].parse::<f64>().ok();
        let int = |i: usize| f[i].parse::<u64>().ok();
        Some(Measure {
            scene: Scene::from_name(f[0])?,
            what: What::from_key(f[1])?,
            threads: int(2)? as usize,
            tile: f[3].parse().ok()?,
            pixels: int(4)? as usize,
            fragments: int(5)?,
            timing: Timing {
                median: num(6)?,
                min: num(7)?,
                max: num(8)?,
                cpu_per_wall: num(9)?,
                cpu: num(10)?,
            },
            peak_rss: int(11)?,
            held: int(12)?,
            prims: int(13)?,
            band_fragments: int(14)?,
        })
    }
}

/// Peak resident memory of this process (`VmHWM` in `/proc/self/status`), bytes; 0 where
/// unavailable.
pub fn peak_rss() -> u64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/status") else {
        return 0;
    };
    s.lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// Measure one configuration in this process (the child's work).
pub fn measure(scene: Scene, what: What, threads: usize, plan: &Plan) -> Result<Measure, String> {
    let (w, h) = plan.size;
    let prims = scene.primitives(w, h, plan.seed);
    let mut out = vec![[0u8; 4]; w as usize * h as usize];
    let mut m = Measure {
        scene,
        what,
        threads,
        tile: plan.tile,
        pixels: out.len(),
        fragments: 0,
        timing: Timing::of(vec![0.0]),
        peak_rss: 0,
        held: 0,
        prims: prims.bytes() as u64,
        band_fragments: 0,
    };
    match what {
        What::Frame(method) => {
            let pool = pool(threads)?;
            let mut r = TiledRenderer::tiled(plan.tile);
            let mut n = 0;
            m.timing = pool.install(|| {
                time(plan.warmup, plan.reps, || {
                    n = r.render(method, &prims, &mut out)?;
                    Ok(())
                })
            })?;
            m.fragments = n;
            m.held = r.held_bytes() as u64;
            m.band_fragments = r.abuffer_peak_fragments() as u64;
        }
        What::Replay => {
            let (sums, cpu, n) = replay_mlab4(&prims, plan.tile, plan.warmup, plan.reps, threads_cpu_seconds)?;
            let wall: f64 = sums.iter().sum::<f64>() / sums.len().max(1) as f64;
            m.timing = Timing {
                cpu_per_wall: cpu / wall,
                cpu,
                ..Timing::of(sums)
            };
            m.fragments = n;
        }
        What::Raster => {
            let mut bins = PrimBins::default();
            let mut n = 0;
            m.timing = time(plan.warmup, plan.reps, || {
                n = raster_only(&prims, &mut bins, plan.tile);
                Ok(())
            })?;
            m.fragments = n;
        }
        What::Idle => {}
    }
    m.peak_rss = peak_rss();
    Ok(m)
}

/// Run [`measure`] in a child process (`exe bench --one SCENE,KEY,THREADS ...`) and parse
/// its line.
pub fn measure_in_child(
    exe: &std::path::Path,
    scene: Scene,
    what: What,
    threads: usize,
    plan: &Plan,
) -> Result<Measure, String> {
    let out = std::process::Command::new(exe)
        .args([
            "bench",
            "--one",
            &format!("{},{},{threads}", scene.name(), what.key()),
            "--size",
            &format!("{}x{}", plan.size.0, plan.size.1),
            "--seed",
            &plan.seed.to_string(),
            "--tile",
            &plan.tile.to_string(),
            "--warmup",
            &plan.warmup.to_string(),
            "--reps",
            &plan.reps.to_string(),
        ])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "{} {} {threads} threads: child failed: {}",
            scene.name(),
            what.key(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    text.lines()
        .find_map(Measure::from_line)
        .ok_or_else(|| format!("child printed no measure: {text}"))
}

/// Every configuration of a bench run, each in a child process: per scene the process with
/// its primitives only, the replay (one thread), every method at every thread count, and MLAB 4
/// at each tile size of `tiles` (one thread and the most threads).
pub fn run(
    exe: &std::path::Path,
    scenes: &[Scene],
    plan: &Plan,
    tiles: &[TileSize],
    mut log: impl FnMut(&Measure),
) -> Result<Vec<Measure>, String> {
    let mut all = Vec::new();
    let mut go = |scene, what, threads, plan: &Plan, all: &mut Vec<Measure>| -> Result<(), String> {
        let m = measure_in_child(exe, scene, what, threads, plan)?;
        log(&m);
        all.push(m);
        Ok(())
    };
    for &scene in scenes {
        go(scene, What::Idle, 1, plan, &mut all)?;
        go(scene, What::Replay, 1, plan, &mut all)?;
        go(scene, What::Raster, 1, plan, &mut all)?;
        for &t in &plan.threads {
            for method in TiledMethod::ALL {
                go(scene, What::Frame(method), t, plan, &mut all)?;
            }
        }
        let tmax = plan.threads.iter().copied().max().unwrap_or(1);
        for &tile in tiles.iter().filter(|&&t| t != plan.tile) {
            let p = Plan { tile, ..plan.clone() };
            let mut ts = vec![1, tmax];
            ts.dedup();
            for t in ts {
                go(scene, What::Frame(TiledMethod::Mlab4), t, &p, &mut all)?;
            }
        }
    }
    Ok(all)
}

/// MLAB 4 against tile size (from the measures of [`run`] with several tile sizes).
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

/// The tables of a bench run (markdown) of a `width`-wide frame.
pub fn tables(all: &[Measure], width: u32) -> String {
    let mut s = String::new();
    s += "## Frame timings (median, spread = (max - min) / median; memory = peak RSS of the child process)\n\n";
    s += "| scene | method | threads | ms (median) | min - max ms | spread | CPU ms | CPU / wall | ns / fragment | CPU ns / fragment | peak RSS MiB | accounted MiB | RSS / accounted | frame path MiB (RSS - idle) | / accounted - primitives | bytes / pixel (RSS) | time / MLAB 4 | CPU / MLAB 4 | CPU / replay |\n";
    s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for m in all.iter().filter(|m| m.what != What::Idle) {
        let find = |what: What, threads: usize| {
            all.iter()
                .find(|x| x.scene == m.scene && x.what == what && x.threads == threads && x.tile == m.tile)
        };
        let ratio = |x: Option<&Measure>| {
            x.map_or("-".to_string(), |x| {
                format!("{:.2}x", m.timing.median / x.timing.median)
            })
        };
        let cpu_ratio =
            |x: Option<&Measure>| x.map_or("-".to_string(), |x| format!("{:.2}x", m.timing.cpu / x.timing.cpu));
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
        s += &format!(
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
        );
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
        let pts: Vec<&Measure> = results
            .iter()
            .filter(|m| m.scene.name() == scene && m.what.name() == what)
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

/// `oit-lab bench`: every scene of `scenes` with every method and thread count of `plan`
/// (and MLAB 4 at the tile sizes `tiles`), each configuration in a child process of this
/// program ([`measure_in_child`]); prints the tables and writes the scaling plot to `svg`.
pub fn command(plan: &Plan, scenes: &[Scene], tiles: &[TileSize], svg: Option<&Path>) -> Result<(), String> {
    let Plan {
        warmup,
        reps,
        ref threads,
        tile,
        size,
        seed,
    } = *plan;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    println!(
        "# oit-lab bench: {}x{}, seed {seed}, tiles {tile} (columns x lines, 0: whole lines), {warmup} warm-up + {reps} timed frames, \
         threads {threads:?} ({cores} cores available), lanes backend {}, one child process per configuration\n",
        size.0,
        size.1,
        mlab::lanes::BACKEND
    );
    let all = run(&exe, scenes, plan, tiles, |m| {
        eprintln!(
            "  {} {} {} threads, tiles {}: {:.2} ms ({:.2} ns/fragment, spread {:.0}%, peak RSS {:.1} MiB)",
            m.scene.name(),
            m.what.name(),
            m.threads,
            m.tile,
            m.timing.median * 1e3,
            m.ns_per_fragment(),
            m.timing.spread_percent(),
            m.peak_rss as f64 / 1048576.0
        )
    })?;
    let (main_runs, band_runs): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|m| m.tile == tile);
    println!("{}", tables(&main_runs, size.0));
    if !band_runs.is_empty() {
        let mut b: Vec<_> = band_runs;
        b.extend(
            main_runs
                .iter()
                .filter(|m| m.what == What::Frame(TiledMethod::Mlab4))
                .cloned(),
        );
        println!("## MLAB 4 against tile size\n\n{}", band_table(&b));
    }
    if let Some(path) = svg {
        let title = format!("Tiled frames, {}x{}, {} cores", size.0, size.1, cores);
        let frames: Vec<_> = main_runs
            .into_iter()
            .filter(|m| matches!(m.what, What::Frame(_)))
            .collect();
        std::fs::write(path, scaling_svg(&frames, &title))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        println!("\nScaling plot: {}", path.display());
    }
    Ok(())
}

/// `oit-lab bench --one`: measure one configuration in this process ([`measure`]) and print
/// its line for the parent.
pub fn child_command(scene: Scene, what: What, threads: usize, plan: &Plan) -> Result<(), String> {
    let m = measure(scene, what, threads.max(1), plan)?;
    println!("{}", m.to_line());
    Ok(())
}
