//! `oit-lab stability` (issue 10): every scene in several primitive orders and seeds
//! ([`super::sweep`]), the quality and change table, the smallest MLAB M and HT K per scene
//! reaching the targets ([`recommendation_table`]) and the strip images ([`strip_picture`]).

use super::sweep::{MethodRun, Plan, SceneStability, Strip, run_scene, table};
use crate::methods::Method;
use crate::methods::catalog::{self, HT_SIZES, MLAB_SIZES};
use crate::out::picture::create_dir;
use crate::out::table::{HT_NOTE, median, progress_bar, spread};
use crate::scenes::Scene;
use std::path::Path;
use std::time::Instant;

/// The recommendation targets of issue 10: PSNR on covered pixels at least this...
pub const TARGET_PSNR: f64 = 40.0;
/// ... and mean FLIP on covered pixels at most this, both at the median over seeds and orders.
pub const TARGET_FLIP: f64 = 0.02;

/// The paper's MLAB configurations (Table 1, 1280x720: 14.1 MB = 2 rows, 28.2 MB = 4 rows;
/// the larger of its two tested configurations in parentheses), for comparison.
pub fn paper_choice(scene: Scene) -> Option<&'static str> {
    match scene {
        Scene::Hair => Some("MLAB 4 (8)"),
        Scene::Particles | Scene::Forest | Scene::Teapots => Some("MLAB 2 (4)"),
        _ => None,
    }
}

/// The smallest method among `candidates` (in order) whose median covered PSNR and FLIP over
/// every seed and order meet the targets, with those medians.
pub fn smallest<'a>(runs: &'a [MethodRun], candidates: &[Method]) -> Option<(&'a MethodRun, f64, f64)> {
    candidates.iter().find_map(|m| {
        let run = runs.iter().find(|r| r.method == *m)?;
        let psnr = median(&run.samples.iter().map(|x| x.psnr).collect::<Vec<_>>());
        let flip = median(&run.samples.iter().map(|x| x.flip).collect::<Vec<_>>());
        (psnr >= TARGET_PSNR && flip <= TARGET_FLIP).then_some((run, psnr, flip))
    })
}

/// The per-scene recommendation: the smallest MLAB M and HT K reaching the targets at the
/// median over seeds and orders (FLIP needs `with_flip`).
pub fn recommendation_table(scenes: &[SceneStability]) -> String {
    let mut s = String::from(
        "| scene | frags / covered px: mean (median over seeds); max | smallest MLAB M | its median PSNR dB / FLIP (covered) | smallest HT K (paper's HT K+1) | its median PSNR dB / FLIP (covered) | paper's choice (Table 1) |\n\
         |---|---:|---:|---:|---:|---:|---|\n",
    );
    let mlab: Vec<Method> = MLAB_SIZES.map(Method::Mlab).to_vec();
    let ht: Vec<Method> = HT_SIZES.map(Method::Hybrid).to_vec();
    for sc in scenes {
        let means: Vec<f64> = sc.depth.iter().map(|d| d.mean).collect();
        let max = sc.depth.iter().map(|d| d.max).max().unwrap_or(0);
        s += &format!("| {} | {}; {max} |", sc.scene.name(), spread(&means, 1, false));
        let biggest = |c: &[Method]| {
            c.iter()
                .rev()
                .find(|m| sc.runs.iter().any(|r| r.method == **m))
                .copied()
        };
        match smallest(&sc.runs, &mlab) {
            Some((r, p, f)) => s += &format!(" {} ({:.0} B/px) | {p:.1} / {f:.3} |", r.method.name(), r.bytes),
            None => s += &format!(" none up to {} | - |", biggest(&mlab).map_or("-".into(), |m| m.name())),
        }
        match smallest(&sc.runs, &ht) {
            Some((r, p, f)) => {
                let k = match r.method {
                    Method::Hybrid(k) => k,
                    _ => 0,
                };
                s += &format!(
                    " {} (HT {}, {:.0} B/px) | {p:.1} / {f:.3} |",
                    r.method.name(),
                    k + 1,
                    r.bytes
                )
            }
            None => s += &format!(" none up to {} | - |", biggest(&ht).map_or("-".into(), |m| m.name())),
        }
        s += &format!(" {} |\n", paper_choice(sc.scene).unwrap_or("-"));
    }
    s += &format!(
        "\nTargets: PSNR >= {TARGET_PSNR} dB and mean FLIP <= {TARGET_FLIP} on covered pixels, both at the median \
         over every seed and order. MLAB M in {MLAB_SIZES:?}, HT K in {HT_SIZES:?}. {}\n",
        HT_NOTE
    );
    s
}

/// Spread levels at which the strip's heat map saturates.
pub const STRIP_SPREAD_LEVELS: u8 = 16;

/// The strip image of a scene: the strip method's images in the first orders of the first
/// seed, side by side at full size, then the per-pixel spread over all that seed's orders as a
/// heat map (nv-flip's magma, 0 to [`STRIP_SPREAD_LEVELS`] levels of the displayed 8-bit sRGB
/// value, largest channel; uncovered pixels grey), each labelled.
pub fn strip_picture(scene: Scene, seed: u64, strip: &Strip) -> crate::out::picture::Picture {
    use crate::out::picture::{LINE, Picture, draw_text};
    let Some((_, first)) = strip.images.first() else {
        return Picture::filled(1, 1, [255; 3]);
    };
    let (w, h) = (first.width, first.height);
    let (gap, scale) = (4u32, 2u32);
    let line = LINE * scale;
    let cols = strip.images.len() as u32 + 1;
    let width = cols * (w + gap) + gap;
    let height = gap + line + gap + h + gap + 2 * line + gap;
    let mut out = Picture::filled(width, height, [255; 3]);
    let black = [0; 3];
    draw_text(
        &mut out,
        gap,
        gap,
        &format!(
            "{}, seed {seed}: {} in {} of {} primitive orders; right: per-pixel spread over all {}",
            scene.name(),
            strip.method.name(),
            strip.images.len(),
            strip.orders,
            strip.orders
        ),
        scale,
        black,
    );
    let y = gap + line + gap;
    for (i, (o, img)) in strip.images.iter().enumerate() {
        let x = gap + i as u32 * (w + gap);
        out.blit(&Picture::from_image(img), x, y);
        let label = if *o == 0 {
            "order 0: the scene's own".to_string()
        } else {
            format!("order {o}: shuffle")
        };
        draw_text(&mut out, x, y + h + 4, &label, scale, black);
    }
    let values: Vec<f32> = strip
        .spread
        .iter()
        .map(|&l| l.min(STRIP_SPREAD_LEVELS) as f32 / STRIP_SPREAD_LEVELS as f32)
        .collect();
    let mut heat = Picture::magma(w, h, &values);
    for (p, &c) in strip.covered.iter().enumerate() {
        if !c {
            heat.data[p * 3..p * 3 + 3].copy_from_slice(&[96; 3]);
        }
    }
    let x = gap + (cols - 1) * (w + gap);
    out.blit(&heat, x, y);
    draw_text(
        &mut out,
        x,
        y + h + 4,
        &format!("spread 0-{STRIP_SPREAD_LEVELS} levels"),
        scale,
        black,
    );
    draw_text(&mut out, x, y + h + 4 + line, "grey: no fragment", scale, black);
    out
}

/// `oit-lab stability`: [`run_scene`] for every scene of `scenes`, the strip images under
/// `out/stability` when `plan.strip` is set; prints the tables.
pub fn command(plan: &Plan, scenes: &[Scene], out: &Path) -> Result<(), String> {
    let start = Instant::now();
    let Plan {
        size,
        ref seeds,
        orders,
        methods: ref all,
        with_flip,
        ..
    } = *plan;
    let pb = progress_bar((scenes.len() * seeds.len() * orders) as u64);
    let mut results = Vec::new();
    for &sc in scenes {
        let r = run_scene(sc, plan, |seed, o| {
            pb.set_message(format!("{} seed {seed} order {o}", sc.name()));
            pb.inc(1);
        })?;
        if let Some(strip) = &r.strip {
            let dir = out.join("stability");
            create_dir(&dir)?;
            strip_picture(sc, seeds[0], strip).write_png_with(
                &dir.join(format!("{}-strip.png", sc.name().to_ascii_lowercase())),
                png::Compression::High,
            )?;
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
        table(&results, &catalog::stability_table())
    );
    if with_flip {
        println!(
            "## Smallest configuration per scene\n\n{}",
            recommendation_table(&results)
        );
    }
    println!(
        "## Every size (covered PSNR and FLIP, min / median / max)\n\n{}",
        table(&results, all)
    );
    if plan.strip.is_some() {
        println!("Strips: {}", out.join("stability").display());
    }
    Ok(())
}
