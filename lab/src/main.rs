//! oit-lab: the command line. See `oit-lab --help`.

use indicatif::{ProgressBar, ProgressStyle};
use oit_lab::dump;
use oit_lab::methods::{BinnedStream, HT_SIZES, MLAB_SIZES, Method};
use oit_lab::metrics::score;
use oit_lab::picture::{Cell, INSET_ZOOM, Picture, Row, counts_picture, densest, labelled_figure};
use oit_lab::report::{Evaluation, evaluate, full_table, summary_table, vis_bias_where};
use oit_lab::scenes::Scene;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

const HELP: &str = "\
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
    --psnr DB         report the smallest MLAB M and HT K reaching this PSNR (default 40)
    --flip X          ... and a mean FLIP at or below X (default: PSNR only)
    --out DIR         write the images there (default: none)
    --no-flip         skip the FLIP metric
    -h, --help        this text

Dump format (little endian): magic OITFRAG1, u32 width, u32 height, 3 x f32 background,
u64 count, then per fragment u32 x, u32 y, f32 depth, 3 x f32 premultiplied color, f32 alpha.
";

const BENCH_HELP: &str = "\
oit-lab bench: whole frames with the tiled renderer (primitives binned into bands, rasterized
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
    --bands A,B,...   also time MLAB 4 at these band heights (1 thread and the most threads)
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

/// A command line error: the message, and whether to show usage (exit code 2) or not (1).
struct Fail(String, bool);

fn usage(m: impl Into<String>) -> Fail {
    Fail(m.into(), true)
}

fn runtime(m: impl Into<String>) -> Fail {
    Fail(m.into(), false)
}

struct Args {
    rest: Vec<String>,
}

impl Args {
    fn flag(&mut self, names: &[&str]) -> bool {
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

fn main() -> ExitCode {
    let mut rest: Vec<String> = std::env::args().skip(1).collect();
    let cmd = match rest.first().map(String::as_str) {
        Some("run") | Some("evaluate") | Some("dump") | Some("bench") | Some("faint") | Some("scenes")
        | Some("stability") | Some("help") => rest.remove(0),
        _ => "run".to_string(),
    };
    let mut args = Args { rest };
    let result = match cmd.as_str() {
        "help" => {
            print!("{HELP}");
            Ok(())
        }
        "evaluate" if args.flag(&["-h", "--help"]) => {
            print!("{EVAL_HELP}");
            Ok(())
        }
        "dump" if args.flag(&["-h", "--help"]) => {
            print!("{DUMP_HELP}");
            Ok(())
        }
        "run" if args.flag(&["-h", "--help"]) => {
            print!("{HELP}\n{RUN_HELP}");
            Ok(())
        }
        "bench" if args.flag(&["-h", "--help"]) => {
            print!("{BENCH_HELP}");
            Ok(())
        }
        "faint" if args.flag(&["-h", "--help"]) => {
            print!("{FAINT_HELP}");
            Ok(())
        }
        "scenes" if args.flag(&["-h", "--help"]) => {
            print!("{SCENES_HELP}");
            Ok(())
        }
        "scenes" => cmd_scenes(args),
        "stability" if args.flag(&["-h", "--help"]) => {
            print!("{STABILITY_HELP}");
            Ok(())
        }
        "stability" => cmd_stability(args),
        "bench" => cmd_bench(args),
        "faint" => cmd_faint(args),
        "evaluate" => cmd_evaluate(args),
        "dump" => cmd_dump(args),
        _ => cmd_run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Fail(m, show_usage)) => {
            eprintln!("error: {m}");
            if show_usage {
                eprintln!("(see oit-lab --help)");
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

fn bar(len: u64) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}] {msg}") {
        pb.set_style(style);
    }
    pb
}

fn mkdir(p: &Path) -> Result<(), Fail> {
    std::fs::create_dir_all(p).map_err(|e| runtime(format!("cannot create {}: {e}", p.display())))
}

/// Gain of the difference images (linear light, [`Picture::difference`]).
const DIFF_GAIN: f32 = 8.0;

/// Write each image, its difference gained in linear light and its FLIP error map through
/// nv-flip's color map, and return the figure row.
fn write_pictures(e: &Evaluation, dir: Option<&Path>) -> Result<(Picture, Vec<(Picture, Picture)>), Fail> {
    let reference = Picture::from_image(&e.reference.image);
    if let Some(d) = dir {
        mkdir(d)?;
        reference.write_png(&d.join("a-buffer.png")).map_err(runtime)?;
    }
    let mut cells = Vec::new();
    for x in &e.entries {
        let img = Picture::from_image(&x.image);
        let diff = Picture::difference(&e.reference.image, &x.image, DIFF_GAIN);
        if let Some(d) = dir {
            let slug = x.method.slug();
            img.write_png(&d.join(format!("{slug}.png"))).map_err(runtime)?;
            diff.write_png(&d.join(format!("{slug}-diff{DIFF_GAIN}x-linear.png")))
                .map_err(runtime)?;
            if let Some(map) = &x.scores.flip_map {
                Picture {
                    width: map.width,
                    height: map.height,
                    data: map.magma(),
                }
                .write_png(&d.join(format!("{slug}-flip.png")))
                .map_err(runtime)?;
            }
        }
        cells.push((img, diff));
    }
    Ok((reference, cells))
}

/// A method's column title in the figure: HT says which HT of the paper it is.
fn figure_title(m: Method) -> String {
    match m {
        Method::Hybrid(k) => format!("HT {k} = paper HT {}", k + 1),
        _ => m.name(),
    }
}

/// The legend lines of the figure.
fn figure_legend(size: (u32, u32), seed: u64) -> Vec<String> {
    vec![
        format!(
            "oit-lab main job, {}x{}, scene seed {seed}, each scene in its own submission order. Per scene, top: the image; the yellow box is shown zoomed in the inset ({INSET_ZOOM}x full size).",
            size.0, size.1
        ),
        "Under each image: PSNR dB / mean FLIP, both over the covered pixels (at least one fragment).".into(),
        format!(
            "Bottom: |method - A-buffer| x{DIFF_GAIN} in LINEAR light (byte = {DIFF_GAIN} x linear difference x 255, no sRGB encoding); under the A-buffer: fragments per pixel (magma)."
        ),
        "HT K = K head rows + tail = the paper's HT K+1 (same bytes as MLAB K+1).".into(),
    ]
}

/// One scene of the labelled figure: the reference with its fragment counts, then each
/// method with its difference image.
fn figure_row(
    e: &Evaluation,
    reference: Picture,
    cells: Vec<(Picture, Picture)>,
    size: (u32, u32),
    factor: u32,
) -> Row {
    let (w, h) = size;
    let (cw, ch) = (w / factor, h / factor);
    let region = densest(&e.counts, w, h, cw * 2 / 5 / INSET_ZOOM, ch * 2 / 5 / INSET_ZOOM);
    let mut out = vec![Cell {
        title: "A-buffer (exact)".into(),
        image: reference,
        caption: "reference".into(),
        lower: counts_picture(&e.counts, w, h),
        lower_caption: format!("fragments/px, 0-{}", e.max_depth),
    }];
    for (x, (img, diff)) in e.entries.iter().zip(cells) {
        let q = &x.scores;
        let psnr = if q.covered.psnr.is_infinite() {
            "inf".to_string()
        } else {
            format!("{:.1}", q.covered.psnr)
        };
        out.push(Cell {
            title: figure_title(x.method),
            image: img,
            caption: match q.flip_covered {
                Some(f) => format!("{psnr} dB / {f:.3}"),
                None => format!("{psnr} dB"),
            },
            lower: diff,
            lower_caption: String::new(),
        });
    }
    Row {
        name: e.name.clone(),
        notes: vec![
            format!("{:.1} frags/px", e.depth.mean),
            format!("(covered), max {}", e.max_depth),
        ],
        region,
        cells: out,
    }
}

/// Methods shown in the small figure (docs/figure.png).
const SMALL: [&str; 8] = [
    "OVER unsorted",
    "MLAB 2",
    "MLAB 4",
    "HT 3",
    "HT 7",
    "AT 4",
    "WBOIT eq.7",
    "Meshkin",
];

fn cmd_run(mut a: Args) -> Result<(), Fail> {
    let mut size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (640, 360),
    };
    if a.flag(&["--hd"]) {
        size = (1280, 720);
    }
    let seed = parse_seed(&mut a)?;
    let scenes = match a.value("--scenes")? {
        Some(list) => list
            .split(',')
            .map(|n| Scene::from_name(n.trim()).ok_or_else(|| usage(format!("--scenes: unknown scene '{n}'"))))
            .collect::<Result<Vec<_>, _>>()?,
        None => Scene::MAIN.to_vec(),
    };
    let out = PathBuf::from(a.value("--out")?.unwrap_or_else(|| "out".into()));
    let with_flip = !a.flag(&["--no-flip"]);
    let pngs = !a.flag(&["--no-png"]);
    a.finish()?;

    let start = Instant::now();
    let methods = Method::standard_list();
    let pb = bar((scenes.len() * (methods.len() + 1)) as u64);
    let mut evals = Vec::new();
    let mut rows = Vec::new();
    let mut small_rows = Vec::new();
    // Cells of the figure: 320 pixels wide at least (640x360 -> 320x180).
    let factor = (size.0 / 320).max(1);
    for sc in &scenes {
        pb.set_message(format!("{}: generating", sc.name()));
        let stream = sc.generate(size.0, size.1, seed);
        let e = evaluate(sc.name(), &stream, &methods, with_flip, |m| {
            pb.set_message(format!("{}: {m}", sc.name()));
            pb.inc(1);
        })
        .map_err(runtime)?;
        let dir = out.join(sc.name().to_ascii_lowercase());
        let (reference, cells) = write_pictures(&e, pngs.then_some(dir.as_path()))?;
        if pngs {
            let row = figure_row(&e, reference, cells, size, factor);
            let mut small = row.clone();
            small.cells = row
                .cells
                .iter()
                .enumerate()
                .filter(|(i, _)| *i == 0 || SMALL.contains(&e.entries[i - 1].method.name().as_str()))
                .map(|(_, c)| c.clone())
                .collect();
            small_rows.push(small);
            rows.push(row);
        }
        evals.push(e);
    }
    pb.finish_and_clear();
    if pngs {
        mkdir(&out)?;
        let legend = figure_legend(size, seed);
        labelled_figure(&rows, factor, &legend)
            .write_png(&out.join("figure.png"))
            .map_err(runtime)?;
        labelled_figure(&small_rows, factor, &legend)
            .write_png_with(&out.join("figure-small.png"), png::Compression::High)
            .map_err(runtime)?;
    }
    println!(
        "# oit-lab: {}x{}, seed {seed}, {} scenes x {} methods, {:.1} s\n",
        size.0,
        size.1,
        scenes.len(),
        methods.len(),
        start.elapsed().as_secs_f64()
    );
    println!(
        "## PSNR (dB) / mean FLIP against the A-buffer\n\n{}",
        summary_table(&evals)
    );
    println!("## All metrics\n\n{}", full_table(&evals));
    println!("## Lanes against scalar (backend {})\n", mlab::lanes::BACKEND);
    for e in &evals {
        let find = |m: Method| e.entries.iter().find(|x| x.method == m).map(|x| &x.image);
        for (scalar, lanes) in [
            (Method::Mlab(4), Method::MlabLanes(4)),
            (Method::Hybrid(3), Method::HybridLanes(3)),
        ] {
            if let (Some(a), Some(b)) = (find(scalar), find(lanes)) {
                let same = a == b;
                println!(
                    "- {}: {} {} {}",
                    e.name,
                    lanes.name(),
                    if same { "==" } else { "DIFFERS FROM" },
                    scalar.name()
                );
            }
        }
    }
    println!();
    for e in evals.iter().filter(|e| e.name == "PARTICLES") {
        println!("## Background visibility bias on PARTICLES (mean signed error, covered pixels)\n");
        println!("| method | >= 1 fragment | >= 32 fragments |\n|---|---:|---:|");
        let (a, b) = (vis_bias_where(e, 1), vis_bias_where(e, 32));
        for ((name, x, n1), (_, y, n2)) in a.iter().zip(&b) {
            println!("| {name} | {x:+.4} ({n1} px) | {y:+.4} ({n2} px) |");
        }
        println!("\n{}\n", oit_lab::report::HT_NOTE);
    }
    if pngs {
        println!("Figure: {}", out.join("figure.png").display());
    }
    Ok(())
}

fn parse_list<T: std::str::FromStr>(a: &mut Args, name: &str) -> Result<Option<Vec<T>>, Fail> {
    let Some(v) = a.value(name)? else { return Ok(None) };
    v.split(',')
        .map(|x| {
            x.trim()
                .parse()
                .map_err(|_| usage(format!("{name}: '{x}' is not a number")))
        })
        .collect::<Result<Vec<T>, _>>()
        .map(Some)
}

fn first<T: Copy>(v: Option<Vec<T>>, default: T) -> T {
    v.and_then(|v| v.first().copied()).unwrap_or(default)
}

fn cmd_bench(mut a: Args) -> Result<(), Fail> {
    use oit_lab::bench::{Plan, What, band_table, measure, run, scaling_svg, tables};
    use oit_lab::tiled::DEFAULT_BAND_LINES;
    let size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (1280, 720),
    };
    let seed = parse_seed(&mut a)?;
    let scenes = parse_scenes(&mut a, &[Scene::Hair, Scene::Particles, Scene::Fog, Scene::Splats])?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = parse_list::<usize>(&mut a, "--threads")?
        .unwrap_or_else(|| [1, 2, 4, 8, 16].into_iter().filter(|&t| t <= cores).collect());
    if threads.contains(&0) {
        return Err(usage("--threads: counts must be at least 1"));
    }
    let band_lines = first(parse_list::<u32>(&mut a, "--band-lines")?, DEFAULT_BAND_LINES).max(1);
    let bands = parse_list::<u32>(&mut a, "--bands")?.unwrap_or_default();
    let warmup = first(parse_list::<usize>(&mut a, "--warmup")?, 2);
    let reps = first(parse_list::<usize>(&mut a, "--reps")?, 7);
    let one = a.value("--one")?;
    let svg = a.value("--svg")?.map(PathBuf::from);
    a.finish()?;
    let plan = Plan {
        warmup,
        reps,
        threads: threads.clone(),
        band_lines,
        size,
        seed,
    };
    if let Some(one) = one {
        // A child: one configuration, one line.
        let parts: Vec<&str> = one.split(',').collect();
        let (Some(scene), Some(what), Some(t)) = (
            parts.first().and_then(|s| Scene::from_name(s)),
            parts.get(1).and_then(|s| What::from_key(s)),
            parts.get(2).and_then(|s| s.parse::<usize>().ok()),
        ) else {
            return Err(usage(format!("--one: expected SCENE,METHOD,THREADS, got '{one}'")));
        };
        let m = measure(scene, what, t.max(1), &plan).map_err(runtime)?;
        println!("{}", m.to_line());
        return Ok(());
    }
    let exe = std::env::current_exe().map_err(|e| runtime(format!("cannot find this program: {e}")))?;
    println!(
        "# oit-lab bench: {}x{}, seed {seed}, bands of {band_lines} lines, {warmup} warm-up + {reps} timed frames, \
         threads {threads:?} ({cores} cores available), lanes backend {}, one child process per configuration\n",
        size.0,
        size.1,
        mlab::lanes::BACKEND
    );
    let all = run(&exe, &scenes, &plan, &bands, |m| {
        eprintln!(
            "  {} {} {} threads, {} lines: {:.2} ms ({:.2} ns/fragment, spread {:.0}%, peak RSS {:.1} MiB)",
            m.scene.name(),
            m.what.name(),
            m.threads,
            m.band_lines,
            m.timing.median * 1e3,
            m.ns_per_fragment(),
            m.timing.spread_percent(),
            m.peak_rss as f64 / 1048576.0
        )
    })
    .map_err(runtime)?;
    let (main_runs, band_runs): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|m| m.band_lines == band_lines);
    println!("{}", tables(&main_runs));
    if !band_runs.is_empty() {
        let mut b: Vec<_> = band_runs;
        b.extend(
            main_runs
                .iter()
                .filter(|m| m.what == What::Frame(oit_lab::tiled::TiledMethod::Mlab4))
                .cloned(),
        );
        println!("## MLAB 4 against band height\n\n{}", band_table(&b));
    }
    if let Some(path) = svg {
        let title = format!("Tiled frames, {}x{}, {} cores", size.0, size.1, cores);
        let frames: Vec<_> = main_runs
            .into_iter()
            .filter(|m| matches!(m.what, What::Frame(_)))
            .collect();
        std::fs::write(&path, scaling_svg(&frames, &title))
            .map_err(|e| runtime(format!("cannot write {}: {e}", path.display())))?;
        println!("\nScaling plot: {}", path.display());
    }
    Ok(())
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

fn cmd_faint(mut a: Args) -> Result<(), Fail> {
    use oit_lab::faint::{tail_stats, tail_table};
    let size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (320, 180),
    };
    let seeds = parse_list::<u64>(&mut a, "--seeds")?.unwrap_or_else(|| vec![1, 2, 3]);
    if seeds.is_empty() {
        return Err(usage("--seeds: at least one seed"));
    }
    let scenes = parse_scenes(&mut a, &Scene::ALL)?;
    let with_flip = !a.flag(&["--no-flip"]);
    let tails = a.flag(&["--tails"]);
    let k = parse_list::<usize>(&mut a, "--tail-k")?
        .and_then(|v| v.first().copied())
        .unwrap_or(3);
    let arith = match a.value("--arith")?.as_deref() {
        None => oit_lab::methods::Arith::DEFAULT,
        Some(n) => oit_lab::methods::Arith::ALL
            .into_iter()
            .find(|x| x.name() == n.to_ascii_lowercase())
            .ok_or_else(|| usage(format!("--arith: '{n}' is not paper or unbiased")))?,
    };
    a.finish()?;
    let start = Instant::now();
    if tails {
        let mut rows = Vec::new();
        for sc in &scenes {
            for &seed in &seeds {
                let stream = sc.generate(size.0, size.1, seed);
                stream
                    .validate()
                    .map_err(|(i, e)| runtime(format!("{}: fragment {i}: {e}", sc.name())))?;
                let binned = BinnedStream::new(&stream);
                rows.push((
                    sc.name().to_string(),
                    seed,
                    tail_stats(&binned, k, arith).map_err(runtime)?,
                ));
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
        return Ok(());
    }
    let methods = oit_lab::faint::methods();
    let mut runs = Vec::new();
    for sc in &scenes {
        for &seed in &seeds {
            let t = Instant::now();
            let stream = sc.generate(size.0, size.1, seed);
            let r = oit_lab::faint::run_stream(*sc, seed, &stream, &methods, with_flip).map_err(runtime)?;
            eprintln!(
                "{} seed {seed}: {} fragments, {:.1} s",
                sc.name(),
                stream.frags.len(),
                t.elapsed().as_secs_f64()
            );
            runs.push(r);
        }
    }
    println!(
        "# oit-lab faint: {}x{}, seeds {seeds:?}, {} scenes x {} methods, {:.1} s\n",
        size.0,
        size.1,
        scenes.len(),
        methods.len(),
        start.elapsed().as_secs_f64()
    );
    println!(
        "Values are median [min, max] over the seeds; covered pixels are those where the reference \
         has at least one fragment; `paper` and `unbiased` are the kernel's arithmetics \
         (`mlab::Paper`, `mlab::Unbiased`, the default).\n"
    );
    println!(
        "## PSNR on covered pixels / mean FLIP, 32 B/px against OVER\n\n{}",
        oit_lab::faint::headline_table(&runs)
    );
    println!("## Every method\n\n{}", oit_lab::faint::full_table(&runs));
    Ok(())
}

fn cmd_scenes(mut a: Args) -> Result<(), Fail> {
    let (w, h) = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (1280, 720),
    };
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

fn cmd_stability(mut a: Args) -> Result<(), Fail> {
    use oit_lab::stability::{Plan, methods, recommendation_table, run_scene, strip_picture, table, table_methods};
    let size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (320, 180),
    };
    let seeds = parse_list::<u64>(&mut a, "--seeds")?.unwrap_or_else(|| vec![1, 2, 3, 4]);
    if seeds.is_empty() {
        return Err(usage("--seeds: at least one seed"));
    }
    let orders = first(parse_list::<usize>(&mut a, "--orders")?, 8);
    if orders < 2 {
        return Err(usage("--orders: at least 2"));
    }
    let scenes = parse_scenes(&mut a, &Scene::MAIN)?;
    let all = methods();
    let strip_name = a.value("--strip")?.unwrap_or_else(|| "MLAB 2".into());
    let strip = all
        .iter()
        .copied()
        .find(|m| m.name().eq_ignore_ascii_case(strip_name.trim()))
        .ok_or_else(|| usage(format!("--strip: '{strip_name}' is not one of the run's methods")))?;
    let out = PathBuf::from(a.value("--out")?.unwrap_or_else(|| "out".into()));
    let with_flip = !a.flag(&["--no-flip"]);
    let pngs = !a.flag(&["--no-png"]);
    a.finish()?;
    let start = Instant::now();
    let plan = Plan {
        size,
        seeds: seeds.clone(),
        orders,
        methods: all.clone(),
        with_flip,
        pair_flip: table_methods(),
        strip: pngs.then_some((strip, 4.min(orders))),
    };
    let pb = bar((scenes.len() * seeds.len() * orders) as u64);
    let mut results = Vec::new();
    for &sc in &scenes {
        let r = run_scene(sc, &plan, |seed, o| {
            pb.set_message(format!("{} seed {seed} order {o}", sc.name()));
            pb.inc(1);
        })
        .map_err(runtime)?;
        if let Some(strip) = &r.strip {
            let dir = out.join("stability");
            mkdir(&dir)?;
            strip_picture(sc, seeds[0], strip)
                .write_png_with(
                    &dir.join(format!("{}-strip.png", sc.name().to_ascii_lowercase())),
                    png::Compression::High,
                )
                .map_err(runtime)?;
        }
        results.push(r);
    }
    pb.finish_and_clear();
    println!(
        "# oit-lab stability: {}x{}, seeds {seeds:?}, {orders} orders each (order 0 the scene's own, \
         1-{} shuffles of its primitives), {} scenes x {} methods, {:.0} s\n",
        size.0,
        size.1,
        orders - 1,
        scenes.len(),
        all.len(),
        start.elapsed().as_secs_f64()
    );
    println!(
        "## Quality over seeds and orders, change between orders\n\n{}",
        table(&results, &table_methods())
    );
    if with_flip {
        println!(
            "## Smallest configuration per scene\n\n{}",
            recommendation_table(&results)
        );
    }
    println!(
        "## Every size (covered PSNR and FLIP, min / median / max)\n\n{}",
        table(&results, &all)
    );
    if pngs {
        println!("Strips: {}", out.join("stability").display());
    }
    Ok(())
}

fn cmd_dump(mut a: Args) -> Result<(), Fail> {
    let scene = a.value("--scene")?.ok_or_else(|| usage("dump needs --scene NAME"))?;
    let scene = Scene::from_name(&scene).ok_or_else(|| usage(format!("--scene: unknown scene '{scene}'")))?;
    let output = a.value("--output")?.ok_or_else(|| usage("dump needs --output FILE"))?;
    let size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (640, 360),
    };
    let seed = parse_seed(&mut a)?;
    a.finish()?;
    let s = scene.generate(size.0, size.1, seed);
    dump::write(Path::new(&output), &s).map_err(|e| runtime(e.to_string()))?;
    println!(
        "{}: {} fragments, {}x{}, written to {output}",
        scene.name(),
        s.frags.len(),
        size.0,
        size.1
    );
    Ok(())
}

fn cmd_evaluate(mut a: Args) -> Result<(), Fail> {
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
    a.finish()?;
    let stream = dump::read(Path::new(&file)).map_err(|e| runtime(e.to_string()))?;
    let methods = Method::standard_list();
    let pb = bar(methods.len() as u64 + 1);
    let name = Path::new(&file)
        .file_name()
        .map_or("dump".into(), |n| n.to_string_lossy().to_string());
    let e = evaluate(&name, &stream, &methods, with_flip, |m| {
        pb.set_message(m.to_string());
        pb.inc(1);
    })
    .map_err(runtime)?;
    pb.finish_and_clear();
    if let Some(d) = &out {
        write_pictures(&e, Some(d))?;
    }
    println!(
        "# oit-lab evaluate {file}: {}x{}, {} fragments\n",
        stream.width,
        stream.height,
        stream.frags.len()
    );
    println!("{}", full_table(std::slice::from_ref(&e)));
    let goal = match flip_target {
        Some(f) => format!("PSNR >= {psnr_target} dB and mean FLIP <= {f} on covered pixels"),
        None => format!("PSNR >= {psnr_target} dB on covered pixels"),
    };
    let binned = BinnedStream::new(&stream);
    // Judged on the covered pixels (where the reference has a fragment): the empty
    // background is right in every method and would lift the PSNR. The whole-image values
    // are printed beside.
    let check = |m: Method| -> Result<(bool, String), Fail> {
        let img = m.render(&binned).map_err(runtime)?;
        let q = score(&e.reference.image, &img, &e.covered, flip_target.is_some());
        let ok = q.covered.psnr >= psnr_target && flip_target.is_none_or(|f| q.flip_covered.is_some_and(|x| x <= f));
        let flip = |v: Option<f64>| v.map_or(String::new(), |f| format!(", FLIP {f:.4}"));
        let line = format!(
            "{}: covered PSNR {:.1} dB{}; whole image PSNR {:.1} dB{}",
            m.name(),
            q.covered.psnr,
            flip(q.flip_covered),
            q.whole.psnr,
            flip(q.whole.flip)
        );
        Ok((ok, line))
    };
    let mut found = None;
    for m in MLAB_SIZES {
        let (ok, line) = check(Method::Mlab(m))?;
        eprintln!("  {line}");
        if ok {
            found = Some(m);
            break;
        }
    }
    match found {
        Some(m) => println!("Smallest MLAB reaching {goal}: M = {m} ({} B/px)", 8 * m),
        None => println!("No MLAB up to M = {} reaches {goal}", MLAB_SIZES[MLAB_SIZES.len() - 1]),
    }
    let mut found = None;
    for k in HT_SIZES {
        let (ok, line) = check(Method::Hybrid(k))?;
        eprintln!("  {line}");
        if ok {
            found = Some(k);
            break;
        }
    }
    match found {
        Some(k) => println!(
            "Smallest HT reaching {goal}: K = {k} head rows + tail, the paper's HT {} ({} B/px)",
            k + 1,
            8 * (k + 1)
        ),
        None => println!(
            "No HT up to K = {} head rows + tail (the paper's HT {}) reaches {goal}",
            HT_SIZES[HT_SIZES.len() - 1],
            HT_SIZES[HT_SIZES.len() - 1] + 1
        ),
    }
    Ok(())
}
