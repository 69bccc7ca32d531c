//! oit-lab: the command line. See `oit-lab --help`.

use indicatif::{ProgressBar, ProgressStyle};
use oit_lab::dump;
use oit_lab::methods::{Frame, HT_SIZES, MLAB_SIZES, Method};
use oit_lab::metrics::compare;
use oit_lab::picture::{Picture, figure};
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
oit-lab bench: composite whole frames (band-binned, rayon) with MLAB 4 lanes, the A-buffer,
WBOIT and OVER; median and spread of repeated runs, thread scaling, memory per frame

USAGE:
    oit-lab bench [OPTIONS]

OPTIONS:
    --size WxH        frame size (default 1280x720)
    --seed N          scene seed (default 1)
    --scenes A,B,...  scenes (default HAIR,PARTICLES)
    --threads 1,2,..  thread counts (default 1, 2, 4, 8, 16 up to the machine's cores)
    --band-lines N    lines per band (default oit_lab::frame::DEFAULT_BAND_LINES)
    --bands A,B,...   also time MLAB 4 at these band heights (all threads)
    --warmup N        untimed runs first (default 3)
    --reps N          timed runs, median reported (default 15)
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
        Some("run") | Some("evaluate") | Some("dump") | Some("bench") | Some("faint") | Some("help") => rest.remove(0),
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

/// Write each image and its 4x difference, and return the figure row.
fn write_pictures(e: &Evaluation, dir: Option<&Path>) -> Result<(Picture, Vec<(Picture, Picture)>), Fail> {
    let reference = Picture::from_image(&e.reference.image);
    if let Some(d) = dir {
        mkdir(d)?;
        reference.write_png(&d.join("a-buffer.png")).map_err(runtime)?;
    }
    let mut cells = Vec::new();
    for x in &e.entries {
        let img = Picture::from_image(&x.image);
        let diff = Picture::difference(&e.reference.image, &x.image, 4.0);
        if let Some(d) = dir {
            img.write_png(&d.join(format!("{}.png", x.method.slug())))
                .map_err(runtime)?;
            diff.write_png(&d.join(format!("{}-diff4x.png", x.method.slug())))
                .map_err(runtime)?;
        }
        cells.push((img, diff));
    }
    Ok((reference, cells))
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
        let small: Vec<_> = e
            .entries
            .iter()
            .zip(&cells)
            .filter(|(x, _)| SMALL.contains(&x.method.name().as_str()))
            .map(|(_, c)| c.clone())
            .collect();
        small_rows.push((reference.clone(), small));
        rows.push((reference, cells));
        evals.push(e);
    }
    pb.finish_and_clear();
    if pngs {
        mkdir(&out)?;
        let f = if size.0 >= 1280 { 8 } else { 4 };
        figure(&rows, f).write_png(&out.join("figure.png")).map_err(runtime)?;
        figure(&small_rows, f * 3 / 2)
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
        println!();
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

fn cmd_bench(mut a: Args) -> Result<(), Fail> {
    use oit_lab::bench::{Plan, bands, run, scaling_svg};
    use oit_lab::frame::{DEFAULT_BAND_LINES, FrameMethod};
    let size = match a.value("--size")? {
        Some(s) => parse_size(&s)?,
        None => (1280, 720),
    };
    let seed = parse_seed(&mut a)?;
    let scenes = match a.value("--scenes")? {
        Some(list) => list
            .split(',')
            .map(|n| Scene::from_name(n.trim()).ok_or_else(|| usage(format!("--scenes: unknown scene '{n}'"))))
            .collect::<Result<Vec<_>, _>>()?,
        None => vec![Scene::Hair, Scene::Particles],
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = parse_list::<usize>(&mut a, "--threads")?
        .unwrap_or_else(|| [1, 2, 4, 8, 16].into_iter().filter(|&t| t <= cores).collect());
    if threads.contains(&0) {
        return Err(usage("--threads: counts must be at least 1"));
    }
    let band_lines = parse_list::<u32>(&mut a, "--band-lines")?
        .and_then(|v| v.first().copied())
        .unwrap_or(DEFAULT_BAND_LINES);
    let band_list = parse_list::<u32>(&mut a, "--bands")?;
    let warmup = parse_list::<usize>(&mut a, "--warmup")?
        .and_then(|v| v.first().copied())
        .unwrap_or(3);
    let reps = parse_list::<usize>(&mut a, "--reps")?
        .and_then(|v| v.first().copied())
        .unwrap_or(15);
    let svg = a.value("--svg")?.map(PathBuf::from);
    a.finish()?;
    let plan = Plan {
        warmup,
        reps,
        threads: threads.clone(),
        band_lines,
    };
    println!(
        "# oit-lab bench: {}x{}, seed {seed}, bands of {band_lines} lines, {warmup} warm-up + {reps} timed runs, \
         threads {threads:?} ({cores} cores available), lanes backend {}\n",
        size.0,
        size.1,
        mlab::lanes::BACKEND
    );
    let mut all = Vec::new();
    let mut band_rows = Vec::new();
    for sc in &scenes {
        let stream = sc.generate(size.0, size.1, seed);
        stream
            .validate()
            .map_err(|(i, e)| runtime(format!("{}: fragment {i}: {e}", sc.name())))?;
        eprintln!("{}: {} fragments", sc.name(), stream.frags.len());
        let r = run(sc.name(), &stream, &plan, |m| {
            eprintln!(
                "  {} {} threads: {:.2} ms ({:.2} ns/fragment, spread {:.0}%)",
                m.what,
                m.threads,
                m.timing.median * 1e3,
                m.ns_per_fragment(),
                m.timing.spread_percent()
            )
        })
        .map_err(runtime)?;
        all.extend(r);
        if let Some(list) = &band_list {
            let t = threads.iter().copied().max().unwrap_or(1);
            for (l, timing) in bands(&stream, &plan, list, t).map_err(runtime)? {
                band_rows.push((sc.name(), l, t, stream.frags.len(), timing));
            }
        }
    }
    // Frame-level table.
    println!("## Frame timings (median of {reps}, spread = (max - min) / median)\n");
    println!(
        "| scene | method | threads | ms (median) | min - max ms | spread | CPU / wall | ns / fragment | frames / s | memory / frame | time / MLAB 4 |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for m in &all {
        let fragments = m.fragments;
        let px = size.0 as usize * size.1 as usize;
        let mem = FrameMethod::ALL
            .into_iter()
            .find(|f| m.what == f.name())
            .map_or("-".to_string(), |f| {
                format!("{:.1} MiB", f.frame_bytes(px, fragments) as f64 / 1048576.0)
            });
        let mlab = all
            .iter()
            .find(|x| x.scene == m.scene && x.threads == m.threads && x.what == FrameMethod::Mlab4.name());
        let ratio = mlab.map_or("-".to_string(), |x| {
            format!("{:.2}x", m.timing.median / x.timing.median)
        });
        println!(
            "| {} ({:.2} M frags) | {} | {} | {:.2} | {:.2} - {:.2} | {:.0}% | {:.2} | {:.2} | {:.1} | {mem} | {ratio} |",
            m.scene,
            fragments as f64 / 1e6,
            m.what,
            m.threads,
            m.timing.median * 1e3,
            m.timing.min * 1e3,
            m.timing.max * 1e3,
            m.timing.spread_percent(),
            m.timing.cpu_per_wall,
            m.ns_per_fragment(),
            1.0 / m.timing.median,
        );
    }
    println!("\n## Scaling (speedup and parallel efficiency over 1 thread)\n");
    println!("| scene | method | threads | speedup | efficiency |\n|---|---|---:|---:|---:|");
    for m in all.iter().filter(|m| m.threads > 1) {
        if let Some(one) = all
            .iter()
            .find(|x| x.scene == m.scene && x.what == m.what && x.threads == 1)
        {
            let s = one.timing.median / m.timing.median;
            println!(
                "| {} | {} | {} | {:.2} | {:.0}% |",
                m.scene,
                m.what,
                m.threads,
                s,
                100.0 * s / m.threads as f64
            );
        }
    }
    if !band_rows.is_empty() {
        println!(
            "\n## MLAB 4: band height\n\n| scene | lines per band | threads | ms (median) | spread | ns / fragment |\n|---|---:|---:|---:|---:|---:|"
        );
        for (scene, l, t, n, timing) in &band_rows {
            println!(
                "| {scene} | {l} | {t} | {:.2} | {:.0}% | {:.2} |",
                timing.median * 1e3,
                timing.spread_percent(),
                timing.median * 1e9 / *n as f64
            );
        }
    }
    println!(
        "\n## Memory per frame at {}x{} (the paper's Table 1 accounting)\n",
        size.0, size.1
    );
    println!("| method | bytes / pixel | MB (MiB) per frame |\n|---|---:|---:|");
    let px = size.0 as f64 * size.1 as f64;
    for (name, bpp) in [
        ("MLAB 2 rows (RGBA8 + f32 depth per row)", 16.0),
        ("MLAB 4 rows", 32.0),
        ("MLAB 8 rows", 64.0),
        ("OVER RGBA16F", 8.0),
        ("WBOIT RGBA16F + R8", 9.0),
    ] {
        println!("| {name} | {bpp} | {:.1} |", bpp * px / 1048576.0);
    }
    for m in all
        .iter()
        .filter(|m| m.what == FrameMethod::ABuffer.name() && m.threads == threads[0])
    {
        let bytes = FrameMethod::ABuffer.frame_bytes(size.0 as usize * size.1 as usize, m.fragments);
        println!(
            "| A-buffer on {} (12 B x {} fragments + 4 B head per pixel) | {:.1} | {:.1} |",
            m.scene,
            m.fragments,
            bytes as f64 / px,
            bytes as f64 / 1048576.0
        );
    }
    if let Some(path) = svg {
        let title = format!("Frame compositing, {}x{}, {} cores", size.0, size.1, cores);
        std::fs::write(&path, scaling_svg(&all, &title))
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
                let frame = Frame::new(&stream);
                rows.push((
                    sc.name().to_string(),
                    seed,
                    tail_stats(&frame, k, arith).map_err(runtime)?,
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
        Some(f) => format!("PSNR >= {psnr_target} dB and mean FLIP <= {f}"),
        None => format!("PSNR >= {psnr_target} dB"),
    };
    let frame = Frame::new(&stream);
    let meets = |m: Method| -> Result<bool, Fail> {
        let img = m.render(&frame).map_err(runtime)?;
        let q = compare(&e.reference.image, &img, flip_target.is_some());
        Ok(q.psnr >= psnr_target && flip_target.is_none_or(|f| q.flip.is_some_and(|x| x <= f)))
    };
    let mut found = None;
    for m in MLAB_SIZES {
        if meets(Method::Mlab(m))? {
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
        if meets(Method::Hybrid(k))? {
            found = Some(k);
            break;
        }
    }
    match found {
        Some(k) => println!("Smallest HT reaching {goal}: K = {k} ({} B/px)", 8 * (k + 1)),
        None => println!("No HT up to K = {} reaches {goal}", HT_SIZES[HT_SIZES.len() - 1]),
    }
    Ok(())
}
