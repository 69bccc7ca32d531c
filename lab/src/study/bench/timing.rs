//! Measuring one configuration of `oit-lab bench` in this process: the plan, repeated
//! timings with their CPU time ([`Timing`], [`time`]), what is timed ([`What`]), the
//! measure and its line for the parent ([`Measure`]), peak resident memory ([`peak_rss`]).

use crate::scenes::Scene;
use crate::tiled::{PrimBins, TileSize, TiledMethod, TiledRenderer, raster_only, replay_mlab4};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct BenchPlan {
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
    /// [`storage_bytes`](crate::tiled::storage_bytes) ([`Method::storage`](crate::methods::Method::storage)).
    pub fn accounted(&self) -> u64 {
        self.held + 4 * self.pixels as u64 + self.prims
    }

    /// What the parent logs of a measure: the configuration, the median time, per fragment,
    /// the spread and the peak resident memory.
    pub fn summary(&self) -> String {
        let what = format!("{} {} {} threads", self.scene.name(), self.what.name(), self.threads);
        let t = &self.timing;
        format!(
            "{what}, tiles {}: {:.2} ms ({:.2} ns/fragment, spread {:.0}%, peak RSS {:.1} MiB)",
            self.tile,
            t.median * 1e3,
            self.ns_per_fragment(),
            t.spread_percent(),
            self.peak_rss as f64 / 1048576.0
        )
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
pub fn measure(scene: Scene, what: What, threads: usize, plan: &BenchPlan) -> Result<Measure, String> {
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
