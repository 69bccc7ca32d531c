//! The tables' shared pieces: number formats ([`num`], [`spread`], [`min_med_max`]), the
//! [`median`], the notes said under the tables ([`HT_NOTE`], [`COVERED_NOTE`]) and the
//! commands' [`progress_bar`].

use indicatif::{ProgressBar, ProgressStyle};

/// How the tables name HT, said once under every table that has an HT row: the lab's
/// `HT K` has `K` head rows plus the tail, which the paper (section 5) calls HT `K + 1`.
pub const HT_NOTE: &str = "HT naming: the lab's `HT K` = K head rows + the tail = the paper's HT K+1 \
                           (8 (K+1) B/px): HT 0, 1, 3, 7 here are the paper's HT 1, 2, 4, 8.";

/// Every covered-pixel column is over the pixels where the reference has at least one
/// fragment; said under the tables.
pub const COVERED_NOTE: &str = "covered: over the pixels with at least one fragment (the rest \
                                show the background in every method); whole: every pixel.";

/// `x` with `digits` decimals; `inf` when infinite.
pub fn num(x: f64, digits: usize) -> String {
    if x.is_infinite() {
        "inf".into()
    } else {
        format!("{x:.digits$}")
    }
}

/// `median [min, max]` of `values` with `digits` decimals (`+` sign when `signed`); just the
/// value when there is one; `-` when none. The median of an even count is the mean of the
/// middle two. Infinite values print as `inf`.
pub fn spread(values: &[f64], digits: usize, signed: bool) -> String {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return "-".into();
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    };
    let f = |x: f64| {
        if x.is_infinite() {
            if x > 0.0 { "inf".to_string() } else { "-inf".to_string() }
        } else if signed {
            format!("{x:+.digits$}")
        } else {
            format!("{x:.digits$}")
        }
    };
    if n == 1 {
        f(median)
    } else {
        format!("{} [{}, {}]", f(median), f(v[0]), f(v[n - 1]))
    }
}

/// Median of the values that are not NaN (the mean of the middle two for an even count);
/// NaN when there is none.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// `min / median / max` of the values that are not NaN, `digits` decimals (`inf` when
/// infinite); `-` when none.
pub fn min_med_max(values: &[f64], digits: usize) -> String {
    let v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return "-".into();
    }
    let f = |x: f64| {
        if x.is_infinite() {
            "inf".to_string()
        } else {
            format!("{x:.digits$}")
        }
    };
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    format!("{} / {} / {}", f(lo), f(median(&v)), f(hi))
}

/// The first line of a command's report: `# NAME: WxH, DETAIL, S scenes x M methods, T s`
/// (seconds with one decimal), and a blank line.
pub fn header(name: &str, size: (u32, u32), detail: &str, counts: (usize, usize), seconds: f64) -> String {
    let (w, h) = size;
    let (scenes, methods) = counts;
    format!("# {name}: {w}x{h}, {detail}, {scenes} scenes x {methods} methods, {seconds:.1} s\n")
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}] {msg}") {
        pb.set_style(style);
    }
    pb
}
