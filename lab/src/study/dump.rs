//! `oit-lab dump`: a scene's fragment stream written as a dump file ([`crate::dump`]).

use crate::dump::write;
use crate::scenes::Scene;

/// `oit-lab dump`: write `scene`'s fragment stream (`size`, `seed`) to `output`, and say so.
pub fn command(scene: Scene, size: (u32, u32), seed: u64, output: &str) -> Result<(), String> {
    let s = scene.generate(size.0, size.1, seed);
    write(std::path::Path::new(output), &s).map_err(|e| e.to_string())?;
    println!(
        "{}: {} fragments, {}x{}, written to {output}",
        scene.name(),
        s.frags.len(),
        size.0,
        size.1
    );
    Ok(())
}
