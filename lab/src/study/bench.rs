//! `oit-lab bench`: frame-level timings of [`crate::tiled`] with warm-up, repetitions,
//! median and spread, thread scaling, peak resident memory, the kernel-only replay bound,
//! the tables and the scaling plot (SVG).
//!
//! Each configuration (scene, method, threads) runs in a child process (`oit-lab bench
//! --one ...`, [`measure`]) so that its peak resident memory (`VmHWM` of
//! `/proc/self/status`) is its own: the child builds the primitives, renders warm-up and
//! timed frames, and prints one [`Measure`] line that the parent parses.

mod tables;
mod timing;

pub use tables::{band_table, scaling_svg, tables};
pub use timing::{
    BenchPlan, Measure, Timing, What, measure, peak_rss, pool, process_cpu_seconds, threads_cpu_seconds, time,
};

use crate::scenes::Scene;
use crate::tiled::{TileSize, TiledMethod};
use std::path::Path;

/// Run [`measure`] in a child process (`exe bench --one SCENE,KEY,THREADS ...`) and parse
/// its line.
pub fn measure_in_child(
    exe: &std::path::Path,
    scene: Scene,
    what: What,
    threads: usize,
    plan: &BenchPlan,
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
    plan: &BenchPlan,
    tiles: &[TileSize],
    mut log: impl FnMut(&Measure),
) -> Result<Vec<Measure>, String> {
    let mut all = Vec::new();
    let mut go = |scene, what, threads, plan: &BenchPlan, all: &mut Vec<Measure>| -> Result<(), String> {
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
            let p = BenchPlan { tile, ..plan.clone() };
            let mut ts = vec![1, tmax];
            ts.dedup();
            for t in ts {
                go(scene, What::Frame(TiledMethod::Mlab4), t, &p, &mut all)?;
            }
        }
    }
    Ok(all)
}

/// `oit-lab bench`: every scene of `scenes` with every method and thread count of `plan`
/// (and MLAB 4 at the tile sizes `tiles`), each configuration in a child process of this
/// program ([`measure_in_child`]); prints the tables and writes the scaling plot to `svg`.
pub fn command(plan: &BenchPlan, scenes: &[Scene], tiles: &[TileSize], svg: Option<&Path>) -> Result<(), String> {
    let BenchPlan {
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
    let all = run(&exe, scenes, plan, tiles, |m| eprintln!("  {}", m.summary()))?;
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
pub fn child_command(scene: Scene, what: What, threads: usize, plan: &BenchPlan) -> Result<(), String> {
    let m = measure(scene, what, threads.max(1), plan)?;
    println!("{}", m.to_line());
    Ok(())
}
