//! The integer RGBA8 resolve (what `Framebuffer::resolve_rgba8` writes, MLAB and HT) against
//! the f32 resolve's RGBA8 (`resolve_into`, then `to_rgba8`) on the lab's main scenes: the share
//! of pixels whose bytes differ and the largest difference, and each resolve's error against the
//! exact composite of what is stored (the rows, or the HT head and tail, in f64) and against the
//! exact composite of the fragments (the A-buffer oracle). For docs/performance.md ("Integer
//! resolve", "Integer HT resolve").
//!
//! `cargo run --release -p oit-lab --example resolve_int [WIDTH HEIGHT SEED]` (default
//! 640 360 1).

use mlab::glam::{Vec3, Vec4};
use mlab::{Arithmetic, Background, Framebuffer, HybridFramebuffer, MlabFramebuffer, Paper, Row, Unbiased, to_rgba8};
use mlab_reference::model::composite_rows_f64;
use oit_lab::scenes::Scene;
use oit_lab::stream::{PixelBins, Stream};

#[derive(Default)]
struct Stats {
    channels: u64,
    /// Channels more than half a step from the exact composite of the rows.
    off: u64,
    worst_rows: f64,
    abs_frag: f64,
    sq_frag: f64,
}

impl Stats {
    fn add(&mut self, byte: u8, rows_exact: f64, frag_exact: f64) {
        let b = f64::from(byte);
        self.channels += 1;
        let e = (b - rows_exact.clamp(0.0, 255.0)).abs();
        if e > 0.5 + 1e-9 {
            self.off += 1;
        }
        self.worst_rows = self.worst_rows.max(e);
        let f = b - frag_exact.clamp(0.0, 255.0);
        self.abs_frag += f.abs();
        self.sq_frag += f * f;
    }
    fn line(&self) -> String {
        let n = self.channels as f64;
        format!(
            "{:.4} % of channels not the nearest byte of the rows' composite, largest error {:.4}; against the fragments: mean |error| {:.4}, RMS {:.4}",
            100.0 * self.off as f64 / n,
            self.worst_rows,
            self.abs_frag / n,
            (self.sq_frag / n).sqrt()
        )
    }
}

/// Both RGBA8 resolves of a filled framebuffer against the exact composites; `exact(i)` is the
/// f64 composite (premultiplied color, visibility) of what pixel `i` stores.
fn compare<F: Framebuffer>(
    label: &str,
    fb: &F,
    stream: &Stream,
    bins: &PixelBins,
    exact: impl Fn(u32, u32) -> [f64; 4],
) {
    let (w, h) = (stream.width, stream.height);
    let bg = stream.background;
    let background = Background::Opaque(Vec3::from(bg));
    let n = (w * h) as usize;
    let mut int = vec![[0u8; 4]; n];
    fb.resolve_rgba8(&mut int, background).expect("size");
    let mut f = vec![Vec4::ZERO; n];
    fb.resolve_into(&mut f, background).expect("size");
    let f32s: Vec<[u8; 4]> = f.iter().map(|&p| to_rgba8(p)).collect();
    let (mut differ, mut largest, mut covered) = (0u64, 0u8, 0u64);
    let (mut si, mut sf) = (Stats::default(), Stats::default());
    let bgd = bg.map(f64::from);
    for i in 0..n {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let frags = bins.of(i);
        if frags.is_empty() {
            continue;
        }
        covered += 1;
        if int[i] != f32s[i] {
            differ += 1;
        }
        for ch in 0..3 {
            largest = largest.max(int[i][ch].abs_diff(f32s[i][ch]));
        }
        let stored = exact(x, y);
        let layers: Vec<mlab::Fragment> = frags
            .iter()
            .map(|&j| stream.frags[j as usize].to_kernel().expect("valid"))
            .collect();
        let (oc, _) = mlab_reference::oracle(&layers, bgd);
        for ch in 0..3 {
            si.add(int[i][ch], stored[ch], 255.0 * oc[ch]);
            sf.add(f32s[i][ch], stored[ch], 255.0 * oc[ch]);
        }
    }
    println!(
        "- {label}: {differ} of {covered} covered pixels differ ({:.3} %), largest difference {largest}",
        100.0 * differ as f64 / covered.max(1) as f64
    );
    println!("  - integer: {}", si.line());
    println!("  - f32:     {}", sf.line());
}

fn run<const M: usize>(stream: &Stream, bins: &PixelBins) {
    let (w, h) = (stream.width, stream.height);
    let mut storage = vec![Row::EMPTY; (w * h) as usize * M];
    let mut fb = MlabFramebuffer::<M>::new(&mut storage, w, h).expect("size");
    for f in &stream.frags {
        let frag = f.to_kernel().expect("valid scene fragments");
        fb.insert(f.pixel % w, f.pixel / w, &frag).expect("inside");
    }
    let bgd = stream.background.map(f64::from);
    let exact = |x, y| {
        let (c, v) = composite_rows_f64(&fb.pixel(x, y).expect("inside"));
        [0, 1, 2, 3].map(|ch| if ch < 3 { 255.0 * (c[ch] + bgd[ch] * v) } else { 255.0 })
    };
    compare(&format!("MLAB M = {M}"), &fb, stream, bins, exact);
}

fn run_ht<const K: usize, A: Arithmetic>(stream: &Stream, bins: &PixelBins) {
    let (w, h) = (stream.width, stream.height);
    let mut storage = vec![Row::EMPTY; HybridFramebuffer::<K, A>::rows_needed(w, h).expect("size")];
    let mut fb = HybridFramebuffer::<K, A>::new_cleared(&mut storage, w, h).expect("size");
    for f in &stream.frags {
        let frag = f.to_kernel().expect("valid scene fragments");
        fb.insert(f.pixel % w, f.pixel / w, &frag).expect("inside");
    }
    let bg = Background::Opaque(Vec3::from(stream.background));
    let exact = |x, y| {
        let (head, tail) = fb.pixel(x, y).expect("inside");
        mlab_reference::resolve_int::ht_exact(&head, tail, bg)
    };
    compare(&format!("HT K = {K}, {}", A::NAME), &fb, stream, bins, exact);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, d: u64| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (w, h, seed) = (num(0, 640) as u32, num(1, 360) as u32, num(2, 1));
    println!("# Integer against f32 RGBA8 resolve, {w}x{h}, seed {seed}, covered pixels only\n");
    for sc in Scene::MAIN {
        let stream = sc.generate(w, h, seed);
        let bins = PixelBins::new(&stream);
        println!("## {} ({} fragments)\n", sc.name(), stream.frags.len());
        run::<1>(&stream, &bins);
        run::<4>(&stream, &bins);
        run::<8>(&stream, &bins);
        run_ht::<3, Unbiased>(&stream, &bins);
        run_ht::<3, Paper>(&stream, &bins);
        run_ht::<7, Unbiased>(&stream, &bins);
        println!();
    }
}
