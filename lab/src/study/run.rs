//! `oit-lab run` (the main job: every scene with every method, the figures and the tables)
//! and `oit-lab evaluate` (the same comparison on a fragment dump, then the smallest and the
//! best bounded-memory methods).
use super::evaluate::{Evaluation, evaluate, full_table, summary_table, vis_bias_where};
use crate::methods::catalog::{self, BUDGETS, HT_SIZES, MLAB_SIZES};
use crate::methods::{BinnedStream, Method};
use crate::metrics::{Scores, score};
use crate::out::figure::{Figures, write_pictures};
use crate::out::table::{HT_NOTE, header, num, progress_bar};
use crate::scenes::Scene;
use std::path::Path;
use std::time::Instant;

/// The main job (`oit-lab run`): every scene of `scenes` at `size` with every method of
/// [`catalog::main_job`]; writes the PNGs and figures under `out` when `pngs`
/// ([`Figures`]), prints the Markdown tables.
pub fn run_command(
    size: (u32, u32),
    seed: u64,
    scenes: &[Scene],
    out: &Path,
    with_flip: bool,
    pngs: bool,
) -> Result<(), String> {
    let start = Instant::now();
    let methods = catalog::main_job();
    let pb = progress_bar((scenes.len() * (methods.len() + 1)) as u64);
    let mut evals = Vec::new();
    let mut figures = Figures::new(size);
    for sc in scenes {
        pb.set_message(format!("{}: generating", sc.name()));
        let stream = sc.generate(size.0, size.1, seed);
        let e = evaluate(sc.name(), &stream, &methods, with_flip, |m| {
            pb.set_message(format!("{}: {m}", sc.name()));
            pb.inc(1);
        })?;
        if pngs {
            figures.add(&e, &out.join(sc.name().to_ascii_lowercase()))?;
        }
        evals.push(e);
    }
    pb.finish_and_clear();
    if pngs {
        figures.write(out, seed)?;
    }
    let counts = (scenes.len(), methods.len());
    let secs = start.elapsed().as_secs_f64();
    println!("{}", header("oit-lab", size, &format!("seed {seed}"), counts, secs));
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
        println!("\n{}\n", HT_NOTE);
    }
    if pngs {
        println!("Figure: {}", out.join("figure.png").display());
    }
    Ok(())
}

/// `oit-lab evaluate`: every method of [`catalog::main_job`] against the A-buffer on the
/// fragment dump `file` (images written to `out` if given), then the smallest MLAB `M` and
/// HT `K` reaching `psnr_target` dB (and a mean FLIP at or below `flip_target`) on the
/// covered pixels, the smallest bounded-memory method reaching it
/// ([`catalog::evaluate_candidates`]: the bounded ones, and MLAB and HT at every size of
/// [`MLAB_SIZES`] and [`HT_SIZES`]), and the best bounded-memory method within each budget of
/// [`BUDGETS`].
pub fn evaluate_command(
    file: &str,
    psnr_target: f64,
    flip_target: Option<f64>,
    out: Option<&Path>,
    with_flip: bool,
) -> Result<(), String> {
    let stream = crate::dump::read(Path::new(&file)).map_err(|e| e.to_string())?;
    let methods = catalog::main_job();
    let pb = progress_bar(methods.len() as u64 + 1);
    let name = Path::new(&file)
        .file_name()
        .map_or("dump".into(), |n| n.to_string_lossy().to_string());
    let e = evaluate(&name, &stream, &methods, with_flip, |m| {
        pb.set_message(m.to_string());
        pb.inc(1);
    })?;
    pb.finish_and_clear();
    if let Some(d) = out {
        write_pictures(&e, Some(d))?;
    }
    println!(
        "# oit-lab evaluate {file}: {}x{}, {} fragments\n",
        stream.width,
        stream.height,
        stream.frags.len()
    );
    println!("{}", full_table(std::slice::from_ref(&e)));
    let goal = Goal {
        psnr: psnr_target,
        flip: flip_target,
    };
    let binned = BinnedStream::new(&stream);
    smallest_sizes(&e, &binned, &goal)?;
    bounded_search(&e, &binned, &goal, with_flip)
}

/// What `oit-lab evaluate` looks for, judged on the covered pixels (where the reference has a
/// fragment: the empty background is right in every method and would lift the PSNR): a PSNR
/// of at least `psnr` dB and, when given, a mean FLIP of at most `flip`.
struct Goal {
    psnr: f64,
    flip: Option<f64>,
}

impl Goal {
    fn met(&self, q: &Scores) -> bool {
        q.covered.psnr >= self.psnr && self.flip.is_none_or(|f| q.flip_covered.is_some_and(|x| x <= f))
    }
}

impl std::fmt::Display for Goal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.flip {
            Some(x) => write!(f, "PSNR >= {} dB and mean FLIP <= {x} on covered pixels", self.psnr),
            None => write!(f, "PSNR >= {} dB on covered pixels", self.psnr),
        }
    }
}

/// The smallest MLAB `M` and HT `K` of the lab's sizes reaching `goal` (each size tried is
/// logged on stderr with its covered and whole-image values), and whether the run-time
/// framebuffer offers that size.
fn smallest_sizes(e: &Evaluation, binned: &BinnedStream, goal: &Goal) -> Result<(), String> {
    let check = |m: Method| -> Result<(bool, String), String> {
        let img = m.render(binned)?;
        let q = score(&e.reference.image, &img, &e.covered, goal.flip.is_some());
        let flip = |v: Option<f64>| v.map_or(String::new(), |f| format!(", FLIP {f:.4}"));
        let line = format!(
            "{}: covered PSNR {:.1} dB{}; whole image PSNR {:.1} dB{}",
            m.name(),
            q.covered.psnr,
            flip(q.flip_covered),
            q.whole.psnr,
            flip(q.whole.flip)
        );
        Ok((goal.met(&q), line))
    };
    // The smallest size of `sizes` whose method reaches the goal.
    let smallest = |sizes: &[usize], method: fn(usize) -> Method| -> Result<Option<usize>, String> {
        for &n in sizes {
            let (ok, line) = check(method(n))?;
            eprintln!("  {line}");
            if ok {
                return Ok(Some(n));
            }
        }
        Ok(None)
    };
    let bytes = |m: Method| m.storage().per_pixel;
    // Sizes the run-time framebuffer (and the C API) offers; larger ones are compile-time
    // sizes of the generic framebuffers (issue 30: a client's cloud got K = 11).
    let runtime = |n: usize, name: &str| {
        if !mlab::Layers::SIZES.contains(&n) {
            println!(
                "  ({name} = {n} is not a size of the run-time DynFramebuffer and the C API ({name} = 1..=8): \
                 use the compile-time size, e.g. SpanFramebuffer::<{n}> or HybridSpanFramebuffer::<{n}>)"
            );
        }
    };
    match smallest(&MLAB_SIZES, Method::Mlab)? {
        Some(m) => {
            println!(
                "Smallest MLAB reaching {goal}: M = {m} ({} B/px)",
                bytes(Method::Mlab(m))
            );
            runtime(m, "M");
        }
        None => println!("No MLAB up to M = {} reaches {goal}", MLAB_SIZES[MLAB_SIZES.len() - 1]),
    }
    match smallest(&HT_SIZES, Method::Hybrid)? {
        Some(k) => {
            println!(
                "Smallest HT reaching {goal}: K = {k} head rows + tail, the paper's HT {} ({} B/px)",
                k + 1,
                bytes(Method::Hybrid(k))
            );
            runtime(k, "K");
        }
        None => println!(
            "No HT up to K = {} head rows + tail (the paper's HT {}) reaches {goal}",
            HT_SIZES[HT_SIZES.len() - 1],
            HT_SIZES[HT_SIZES.len() - 1] + 1
        ),
    }
    Ok(())
}

/// Every bounded-memory method (issue 25; MLAB and HT at every size the lab has,
/// [`catalog::evaluate_candidates`]): the smallest reaching `goal`, and the best within each
/// budget of [`BUDGETS`].
fn bounded_search(e: &Evaluation, binned: &BinnedStream, goal: &Goal, with_flip: bool) -> Result<(), String> {
    let mut scored = Vec::new();
    for m in catalog::evaluate_candidates() {
        let img = m.render(binned)?;
        let q = score(&e.reference.image, &img, &e.covered, with_flip);
        scored.push((m, m.storage().per_pixel, q.covered.psnr, q.flip_covered, goal.met(&q)));
    }
    scored.sort_by_key(|x| x.1);
    let show = |(m, b, p, f, _): &(Method, usize, f64, Option<f64>, bool)| {
        let f = f.map_or(String::new(), |f| format!(", FLIP {f:.4}"));
        format!("{} ({b} B/px, covered PSNR {}{f})", m.name(), num(*p, 1))
    };
    match scored.iter().find(|x| x.4) {
        Some(x) => println!("Smallest bounded-memory method reaching {goal}: {}", show(x)),
        None => println!("No bounded-memory method reaches {goal}"),
    }
    println!("\nBest bounded-memory method per budget (covered pixels):\n");
    println!("| budget B/px | best by PSNR | best by FLIP |\n|---:|---|---|");
    for budget in BUDGETS {
        let fit: Vec<_> = scored.iter().filter(|x| x.1 <= budget).collect();
        let by_psnr = fit.iter().max_by(|a, b| a.2.total_cmp(&b.2));
        let by_flip = fit
            .iter()
            .filter(|x| x.3.is_some())
            .min_by(|a, b| a.3.unwrap_or(f64::NAN).total_cmp(&b.3.unwrap_or(f64::NAN)));
        println!(
            "| {budget} | {} | {} |",
            by_psnr.map_or("-".into(), |x| show(x)),
            by_flip.map_or("-".into(), |x| show(x))
        );
    }
    Ok(())
}
