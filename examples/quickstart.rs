//! Composite a few transparent fragments, submitted out of order, into one pixel with MLAB
//! (2 rows) and Hybrid Transparency (1 head row + tail, the same 16 bytes), and print them
//! next to the exact answer.
//!
//! `cargo run --release --example quickstart`

use mlab::glam::Vec3;
use mlab::{BlendingArray, Fragment, FragmentError, Hybrid};

fn main() -> Result<(), FragmentError> {
    // (straight color, alpha, depth), in submission order (not sorted).
    let stream = [
        (Vec3::new(1.0, 0.2, 0.2), 0.5, 3.0), // red, far
        (Vec3::new(0.2, 1.0, 0.2), 0.4, 1.0), // green, near
        (Vec3::new(0.2, 0.2, 1.0), 0.6, 2.0), // blue, between: MLAB's merge error case
        (Vec3::new(1.0, 1.0, 0.0), 0.0, 1.5), // invisible (alpha 0, straight color -> 0)
        (Vec3::new(0.9, 0.9, 0.9), 0.3, 0.5), // white haze, nearest
    ];
    let background = Vec3::new(0.1, 0.1, 0.1);

    let mut mlab = BlendingArray::<2>::new();
    let mut ht = Hybrid::<1>::new();
    let mut fragments = Vec::new();
    for (color, alpha, depth) in stream {
        let f = Fragment::straight(color, alpha, depth)?;
        mlab.insert(&f);
        ht.insert(&f);
        fragments.push(f);
    }

    // Exact: sort front to back (on equal depth the later submission in front, as Listing 1
    // puts it: reversed, then a stable sort) and composite. These few lines keep the example
    // self-contained; the tests, fuzz targets and lab share the f64 oracle of `mlab-reference`.
    fragments.reverse();
    fragments.sort_by(|a, b| a.depth().partial_cmp(&b.depth()).expect("finite depths"));
    let (mut color, mut visibility) = (Vec3::ZERO, 1.0);
    for f in &fragments {
        color += f.color() * visibility;
        visibility *= 1.0 - f.alpha();
    }
    let exact = color + background * visibility;

    let m = mlab.resolve().over(background);
    let h = ht.resolve().over(background);
    println!("exact      {:.4} {:.4} {:.4}", exact.x, exact.y, exact.z);
    println!(
        "MLAB M=2   {:.4} {:.4} {:.4}  (16 bytes: {:?})",
        m.x,
        m.y,
        m.z,
        mlab.rows()
    );
    println!(
        "HT   K=1   {:.4} {:.4} {:.4}  (16 bytes: {:?}, {:?})",
        h.x,
        h.y,
        h.z,
        ht.head(),
        ht.tail()
    );
    println!(
        "max error  MLAB {:.4}, HT {:.4}",
        (m - exact).abs().max_element(),
        (h - exact).abs().max_element()
    );
    Ok(())
}
