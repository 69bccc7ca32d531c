//! The command line of `oit-lab`: the help texts, the argument list ([`Args`]), the parsers
//! (`--size`, `--seed`, lists, scenes, seeds) and, per command, the reading of its options into
//! the call of its study (`oit_lab::study::*`). `main.rs` only dispatches.

use oit_lab::methods::{Arith, catalog};
use oit_lab::scenes::Scene;
use oit_lab::study::{bench, dump, faint, peers, run, stability, sweep};
use oit_lab::tiled::TileSize;
use std::path::PathBuf;

pub const HELP: &str = "\
oit-lab: compare order-independent transparency methods with the exact A-buffer

USAGE:
    oit-lab [run] [OPTIONS]                 render every scene with every method (the main job)
    oit-lab evaluate --fragments FILE [OPTIONS]
                                            the same comparison on a fragment dump
    oit-lab dump --scene NAME --output FILE [OPTIONS]
                                            write a scene's fragment stream as a dump
    oit-lab bench [OPTIONS]                 frame-level timings on every core (docs/frame.md)
    oit-lab faint [OPTIONS]                 issue 9: faint and dense layers, both arithmetics
    oit-lab scenes [OPTIONS]                fragments per scene and per covered pixel (default
                                            1280x720, against the paper's Table 1)
    oit-lab stability [OPTIONS]             issue 10: every scene in several primitive orders and
                                            seeds: quality spreads, change between orders,
                                            the smallest M and K per scene
    oit-lab peers [OPTIONS]                 issue 25: MLAB against the bounded-memory methods (moment-
                                            based OIT, K-closest, HT, WBOIT, ...) by memory budget over
                                            seeds and orders, and their flicker under a moving camera
    oit-lab help | --help | -h              this text; `oit-lab COMMAND --help` for a command

The main job writes OUT/figure.png (Figure 3 grid), OUT/figure-small.png, one PNG per image
and difference image under OUT/SCENE/, and prints the Markdown tables. OUT is ./out.
";

const RUN_HELP: &str = "\
oit-lab run: render every scene with every method and compare with the A-buffer

USAGE:
    oit-lab [run] [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 640x360)
    --hd              same as --size 1280x720 (millions of fragments per scene)
    --seed N          scene seed (default 1)
    --scenes A,B,...  only these scenes (default HAIR, PARTICLES, FOREST, TEAPOTS or PWRPLANT,
                      GLASS; FOG and SPLATS can be named too)
    --out DIR         output folder (default out, relative to the current folder)
    --no-flip         skip the FLIP metric
    --no-png          write no PNG files
    -h, --help        this text
";

const EVAL_HELP: &str = "\
oit-lab evaluate: compare every method with the A-buffer on a fragment dump

USAGE:
    oit-lab evaluate --fragments FILE [OPTIONS]

OPTIONS:
    --fragments FILE  the dump (format: lab/src/dump.rs, docs/quality.md)
    --psnr DB         report the smallest MLAB M and HT K reaching this PSNR (default 40), the
                      smallest bounded-memory method of any kind reaching it, and the best
                      bounded-memory method within 8, 16, 32 and 64 B/px
    --flip X          ... and a mean FLIP at or below X (default: PSNR only)
    --out DIR         write the images there (default: none)
    --no-flip         skip the FLIP metric
    -h, --help        this text

Dump format (little endian): magic OITFRAG2, u32 width, u32 height, 3 x f32 background,
u64 count, then per fragment u32 x, u32 y, f32 depth, 3 x f32 premultiplied color, f32 alpha,
u32 key (the primitive's id); OITFRAG1 files (no key: fragments keyed by their index) still load.
";

const BENCH_HELP: &str = "\
oit-lab bench: whole frames with the tiled renderer (primitives binned into tiles, rasterized
straight into each method's target, rayon): MLAB 4 (both arithmetics), the A-buffer, WBOIT and
OVER, and the kernel-only replay of MLAB 4's span inserts; median and spread of repeated frames,
thread scaling, peak resident memory of a child process per configuration

USAGE:
    oit-lab bench [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 1280x720)
    --seed N          scene seed (default 1)
    --scenes A,B,...  scenes (default HAIR,PARTICLES,FOG,SPLATS)
    --threads 1,2,..  thread counts (default 1, 2, 4, 8, 16 up to the machine's cores)
    --band-lines N    lines per band (default oit_lab::tiled::DEFAULT_BAND_LINES)
    --tile-width N    columns per tile, a multiple of 8 (default 0: whole lines)
    --tile WxL        both at once (W 0: whole lines)
    --bands A,B,...   also time MLAB 4 at these tile sizes, each L (whole lines) or WxL
                      (1 thread and the most threads)
    --warmup N        untimed frames first (default 2)
    --reps N          timed frames, median reported (default 7)
    --one S,M,T       (internal) measure scene S, method M, T threads in this process
    --svg FILE        write the scaling plot there
    -h, --help        this text
";

const FAINT_HELP: &str = "\
oit-lab faint: many faint or dense layers (issue 9). Renders every scene with MLAB 1, 2, 4, 8
and HT at the same memory (K = 0, 1, 3, 7), each with the paper's arithmetic and with the
unbiased one, and unsorted OVER; prints per scene PSNR on covered pixels, mean FLIP, the
background-visibility bias (mean and max over covered pixels) and saturated HT tails, over
several seeds (min / median / max).

USAGE:
    oit-lab faint [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 320x180)
    --seeds A,B,...   scene seeds (default 1,2,3)
    --scenes A,B,...  only these scenes (default all seven: HAIR, PARTICLES, FOREST,
                      TEAPOTS or PWRPLANT, GLASS, FOG, SPLATS)
    --no-flip         skip the FLIP metric
    --tails           print only the HT tail sums (no rendering): per scene and seed, the
                      sums over each pixel's fragments beyond the nearest K, in units of 1/255
    --tail-k K        head rows for --tails (default 3)
    --arith NAME      quantization for --tails: paper or unbiased (default unbiased)
    -h, --help        this text
";

const SCENES_HELP: &str = "\
oit-lab scenes: how deep each scene is: fragments in the frame, covered pixels, mean, 99th
percentile and max fragments per covered pixel, the paper's Table 1 count (1280x720), and the
share of covered pixels whose exact image exceeds 1 (clipped by a display and by the metrics)

USAGE:
    oit-lab scenes [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 1280x720, the paper's)
    --seed N          scene seed (default 1)
    --scenes A,B,...  these scenes (default the main five; FOG and SPLATS have tens of
                      millions of fragments at 640x360 already)
    --no-clip         skip the clipped share (it renders the exact image)
    -h, --help        this text
";

const STABILITY_HELP: &str = "\
oit-lab stability: every scene submitted in several primitive orders (order 0 is the scene's own,
the others seeded shuffles of its primitive list) for several scene seeds; per method the covered
PSNR and FLIP min / median / max over seeds and orders, the change between consecutive orders
(mean FLIP, share of covered pixels moving by more than 2/255), the per-pixel spread over all
orders, and the smallest MLAB M and HT K reaching PSNR >= 40 dB and FLIP <= 0.02 on covered
pixels at the median. Writes OUT/stability/SCENE-strip.png (one method in several orders and its
per-pixel spread). About 4-5 minutes with the defaults on 2 cores.

USAGE:
    oit-lab stability [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 320x180)
    --seeds A,B,...   scene seeds (default 1,2,3,4)
    --orders N        primitive orders per seed, at least 2 (default 8)
    --scenes A,B,...  scenes (default HAIR, PARTICLES, FOREST, TEAPOTS, GLASS)
    --strip NAME      method of the strip images (default \"MLAB 2\")
    --out DIR         output folder (default out)
    --no-flip         skip FLIP (the recommendation then cannot be made)
    --no-png          write no strip images
    -h, --help        this text
";

const PEERS_HELP: &str = "\
oit-lab peers: every scene in several seeds and primitive orders with the bounded-memory methods
(OVER, MLAB 1-4 and 8, HT 0/1/3/7, K-closest 2/4/8, moment-based OIT: power 4/6 and trigonometric
2/3 at 16 and 32 bits, WBOIT, Bavoil-Myers, Meshkin) and AT 4; per memory budget (8, 16, 32, 64
B/px) the best method by median PSNR and by median FLIP on covered pixels, MLAB 4 against the best
other method at <= 32 B/px, and the flicker each adds to the reference's along a seeded camera path
(16 frames of a slow dolly with drift).

USAGE:
    oit-lab peers [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 320x180)
    --seeds A,B,...   scene seeds (default 1,2,3; the camera path uses the first)
    --orders N        primitive orders per seed (default 2: the scene's own and a shuffle)
    --scenes A,B,...  scenes (default all seven)
    --no-flip         skip FLIP
    --no-camera       skip the camera path
    -h, --help        this text
";

const DUMP_HELP: &str = "\
oit-lab dump: write a scene's fragment stream as a dump file

USAGE:
    oit-lab dump --scene NAME --output FILE [--size WxH] [--seed N]

OPTIONS:
    --scene NAME      HAIR, PARTICLES, FOREST, TEAPOTS (or PWRPLANT), GLASS, FOG, SPLATS
    --output FILE     where to write
    --size WxH        frame size (default 640x360)
    --seed N          scene seed (default 1)
    -h, --help        this text
";

/// The help text of `cmd` (`oit-lab run --help` shows the overview first).
pub fn help_of(cmd: &str) -> String {
    match cmd {
        "evaluate" => EVAL_HELP.into(),
        "dump" => DUMP_HELP.into(),
        "bench" => BENCH_HELP.into(),
        "faint" => FAINT_HELP.into(),
        "scenes" => SCENES_HELP.into(),
        "stability" => STABILITY_HELP.into(),
        "peers" => PEERS_HELP.into(),
        _ => format!("{HELP}\n{RUN_HELP}"),
    }
}

/// A command line error: the message, and whether to show usage (exit code 2) or not (1).
pub struct Fail(pub String, pub bool);

fn usage(m: impl Into<String>) -> Fail {
    Fail(m.into(), true)
}

fn runtime(m: impl Into<String>) -> Fail {
    Fail(m.into(), false)
}

pub struct Args {
    pub rest: Vec<String>,
}

impl Args {
    pub fn flag(&mut self, names: &[&str]) -> bool {
        let before = self.rest.len();
        self.rest.retain(|a| !names.contains(&a.as_str()));
        self.rest.len() != before
    }

    fn value(&mut self, name: &str) -> Result<Option<String>, Fail> {
        let Some(i) = self.rest.iter().position(|a| a == name) else {
            return Ok(None);
        };
        if i + 1 >= self.rest.len() {
            return Err(usage(format!("{name} needs a value")));
        }
        let v = self.rest.remove(i + 1);
        self.rest.remove(i);
        Ok(Some(v))
    }

    fn finish(self) -> Result<(), Fail> {
        match self.rest.first() {
            Some(a) => Err(usage(format!("unexpected argument '{a}'"))),
            None => Ok(()),
        }
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), Fail> {
    let bad = || usage(format!("--size: '{s}' is not WIDTHxHEIGHT within 8x8..=8192x8192"));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if !(8..=8192).contains(&w) || !(8..=8192).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

fn parse_seed(a: &mut Args) -> Result<u64, Fail> {
    match a.value("--seed")? {
        Some(s) => s
            .parse()
            .map_err(|_| usage(format!("--seed: '{s}' is not a non-negative integer"))),
        None => Ok(1),
    }
}

fn parse_size_or(a: &mut Args, default: (u32, u32)) -> Result<(u32, u32), Fail> {
    match a.value("--size")? {
        Some(s) => parse_size(&s),
        None => Ok(default),
    }
}

fn parse_list<T: std::str::FromStr>(a: &mut Args, name: &str) -> Result<Option<Vec<T>>, Fail> {
    let Some(v) = a.value(name)? else { return Ok(None) };
    v.split(',')
        .map(|x| {
            x.trim()
                .parse()
                .map_err(|_| usage(format!("{name}: '{x}' is not a valid value")))
        })
        .collect::<Result<Vec<T>, _>>()
        .map(Some)
}

fn first<T: Copy>(v: Option<Vec<T>>, default: T) -> T {
    v.and_then(|v| v.first().copied()).unwrap_or(default)
}

fn parse_scenes(a: &mut Args, default: &[Scene]) -> Result<Vec<Scene>, Fail> {
    match a.value("--scenes")? {
        Some(list) => list
            .split(',')
            .map(|n| Scene::from_name(n.trim()).ok_or_else(|| usage(format!("--scenes: unknown scene '{n}'"))))
            .collect(),
        None => Ok(default.to_vec()),
    }
}

fn parse_seeds(a: &mut Args, default: &[u64]) -> Result<Vec<u64>, Fail> {
    let seeds = parse_list::<u64>(a, "--seeds")?.unwrap_or_else(|| default.to_vec());
    if seeds.is_empty() {
        return Err(usage("--seeds: at least one seed"));
    }
    Ok(seeds)
}

/// A sweep's size, seeds, orders and scenes.
type Sweep = ((u32, u32), Vec<u64>, usize, Vec<Scene>);

/// The options of a sweep over seeds and orders (stability, peers), in this order: `--size`
/// (default 320x180), `--seeds`, `--orders` (checked or adjusted by `orders_ok`), `--scenes`.
fn parse_sweep(
    a: &mut Args,
    seeds: &[u64],
    orders: usize,
    orders_ok: impl Fn(usize) -> Result<usize, Fail>,
    scenes: &[Scene],
) -> Result<Sweep, Fail> {
    let size = parse_size_or(a, (320, 180))?;
    let seeds = parse_seeds(a, seeds)?;
    let orders = orders_ok(first(parse_list::<usize>(a, "--orders")?, orders))?;
    Ok((size, seeds, orders, parse_scenes(a, scenes)?))
}

pub fn cmd_run(mut a: Args) -> Result<(), Fail> {
    let mut size = parse_size_or(&mut a, (640, 360))?;
    if a.flag(&["--hd"]) {
        size = (1280, 720);
    }
    let seed = parse_seed(&mut a)?;
    let scenes = parse_scenes(&mut a, &Scene::MAIN)?;
    let out = PathBuf::from(a.value("--out")?.unwrap_or_else(|| "out".into()));
    let with_flip = !a.flag(&["--no-flip"]);
    let pngs = !a.flag(&["--no-png"]);
    a.finish()?;
    run::run_command(size, seed, &scenes, &out, with_flip, pngs).map_err(runtime)
}

pub fn cmd_bench(mut a: Args) -> Result<(), Fail> {
    let size = parse_size_or(&mut a, (1280, 720))?;
    let seed = parse_seed(&mut a)?;
    let scenes = parse_scenes(&mut a, &[Scene::Hair, Scene::Particles, Scene::Fog, Scene::Splats])?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = parse_list::<usize>(&mut a, "--threads")?
        .unwrap_or_else(|| [1, 2, 4, 8, 16].into_iter().filter(|&t| t <= cores).collect());
    if threads.contains(&0) {
        return Err(usage("--threads: counts must be at least 1"));
    }
    let band_lines = first(
        parse_list::<u32>(&mut a, "--band-lines")?,
        oit_lab::tiled::DEFAULT_BAND_LINES,
    )
    .max(1);
    let tile_width = first(
        parse_list::<u32>(&mut a, "--tile-width")?,
        oit_lab::tiled::DEFAULT_TILE_WIDTH,
    );
    let mut tile = TileSize {
        width: tile_width,
        lines: band_lines,
    };
    if let Some(t) = parse_list::<TileSize>(&mut a, "--tile")? {
        tile = first(Some(t), tile);
    }
    let bands = parse_list::<TileSize>(&mut a, "--bands")?.unwrap_or_default();
    let warmup = first(parse_list::<usize>(&mut a, "--warmup")?, 2);
    let reps = first(parse_list::<usize>(&mut a, "--reps")?, 7);
    let one = a.value("--one")?;
    let svg = a.value("--svg")?.map(PathBuf::from);
    a.finish()?;
    let plan = bench::BenchPlan {
        warmup,
        reps,
        threads,
        tile,
        size,
        seed,
    };
    if let Some(one) = one {
        // A child: one configuration, one line.
        let parts: Vec<&str> = one.split(',').collect();
        let (Some(scene), Some(what), Some(t)) = (
            parts.first().and_then(|s| Scene::from_name(s)),
            parts.get(1).and_then(|s| bench::What::from_key(s)),
            parts.get(2).and_then(|s| s.parse::<usize>().ok()),
        ) else {
            return Err(usage(format!("--one: expected SCENE,METHOD,THREADS, got '{one}'")));
        };
        return bench::child_command(scene, what, t, &plan).map_err(runtime);
    }
    bench::command(&plan, &scenes, &bands, svg.as_deref()).map_err(runtime)
}

pub fn cmd_faint(mut a: Args) -> Result<(), Fail> {
    let size = parse_size_or(&mut a, (320, 180))?;
    let seeds = parse_seeds(&mut a, &[1, 2, 3])?;
    let scenes = parse_scenes(&mut a, &Scene::ALL)?;
    let with_flip = !a.flag(&["--no-flip"]);
    let tails = a.flag(&["--tails"]);
    let k = parse_list::<usize>(&mut a, "--tail-k")?
        .and_then(|v| v.first().copied())
        .unwrap_or(3);
    let arith = match a.value("--arith")?.as_deref() {
        None => Arith::default(),
        Some(n) => Arith::ALL
            .into_iter()
            .find(|x| x.name() == n.to_ascii_lowercase())
            .ok_or_else(|| usage(format!("--arith: '{n}' is not paper or unbiased")))?,
    };
    a.finish()?;
    if tails {
        faint::tails_command(size, &seeds, &scenes, k, arith).map_err(runtime)
    } else {
        faint::command(size, &seeds, &scenes, with_flip).map_err(runtime)
    }
}

pub fn cmd_scenes(mut a: Args) -> Result<(), Fail> {
    let (w, h) = parse_size_or(&mut a, (1280, 720))?;
    let seed = parse_seed(&mut a)?;
    let scenes = parse_scenes(&mut a, &Scene::MAIN)?;
    let clip = !a.flag(&["--no-clip"]);
    a.finish()?;
    println!("# Scene depth: {w}x{h}, seed {seed}\n");
    print!(
        "{}",
        oit_lab::scenes::stats::table(&scenes, w, h, seed, clip).map_err(runtime)?
    );
    Ok(())
}

pub fn cmd_stability(mut a: Args) -> Result<(), Fail> {
    let at_least_2 = |o| {
        if o < 2 {
            Err(usage("--orders: at least 2"))
        } else {
            Ok(o)
        }
    };
    let (size, seeds, orders, scenes) = parse_sweep(&mut a, &[1, 2, 3, 4], 8, at_least_2, &Scene::MAIN)?;
    let with_flip = !a.flag(&["--no-flip"]);
    let pngs = !a.flag(&["--no-png"]);
    let all = catalog::stability();
    let strip_name = a.value("--strip")?.unwrap_or_else(|| "MLAB 2".into());
    let strip = all
        .iter()
        .copied()
        .find(|m| m.name().eq_ignore_ascii_case(strip_name.trim()))
        .ok_or_else(|| usage(format!("--strip: '{strip_name}' is not one of the run's methods")))?;
    let out = PathBuf::from(a.value("--out")?.unwrap_or_else(|| "out".into()));
    a.finish()?;
    let plan = sweep::Plan {
        size,
        seeds,
        orders,
        methods: all,
        with_flip,
        pair_flip: catalog::stability_table(),
        strip: pngs.then_some((strip, 4.min(orders))),
    };
    stability::command(&plan, &scenes, &out).map_err(runtime)
}

pub fn cmd_peers(mut a: Args) -> Result<(), Fail> {
    let (size, seeds, orders, scenes) = parse_sweep(&mut a, &[1, 2, 3], 2, |o| Ok(o.max(1)), &Scene::ALL)?;
    let with_flip = !a.flag(&["--no-flip"]);
    let camera = !a.flag(&["--no-camera"]);
    a.finish()?;
    let plan = peers::PeersPlan {
        size,
        seeds,
        orders,
        with_flip,
        camera,
    };
    peers::command(&plan, &scenes).map_err(runtime)
}

pub fn cmd_dump(mut a: Args) -> Result<(), Fail> {
    let scene = a.value("--scene")?.ok_or_else(|| usage("dump needs --scene NAME"))?;
    let scene = Scene::from_name(&scene).ok_or_else(|| usage(format!("--scene: unknown scene '{scene}'")))?;
    let output = a.value("--output")?.ok_or_else(|| usage("dump needs --output FILE"))?;
    let size = parse_size_or(&mut a, (640, 360))?;
    let seed = parse_seed(&mut a)?;
    a.finish()?;
    dump::command(scene, size, seed, &output).map_err(runtime)
}

pub fn cmd_evaluate(mut a: Args) -> Result<(), Fail> {
    let file = a
        .value("--fragments")?
        .ok_or_else(|| usage("evaluate needs --fragments FILE"))?;
    let psnr_target = match a.value("--psnr")? {
        Some(s) => s
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| usage(format!("--psnr: '{s}' is not a number")))?,
        None => 40.0,
    };
    let flip_target = match a.value("--flip")? {
        Some(s) => Some(
            s.parse::<f64>()
                .ok()
                .filter(|x| (0.0..=1.0).contains(x))
                .ok_or_else(|| usage(format!("--flip: '{s}' is not a number in [0, 1]")))?,
        ),
        None => None,
    };
    let out = a.value("--out")?.map(PathBuf::from);
    let with_flip = !a.flag(&["--no-flip"]) || flip_target.is_some();
    run::evaluate_command(&file, psnr_target, flip_target, out.as_deref(), with_flip).map_err(runtime)
}
