//! The core clock by measurement (`cargo bench --bench clock`): a chain of dependent 64-bit
//! adds, one per cycle on every x86-64 core, timed in CPU time (user + system of this
//! process, from `/proc/self/stat`), so that other load on a shared machine does not count.
//! `/proc/cpuinfo` reports the base clock of a VM, not the clock the code runs at.

#[cfg(target_arch = "x86_64")]
fn dependent_adds(n: u64) -> u64 {
    let mut x: u64 = 0;
    let mut left = n;
    // SAFETY: register-only arithmetic on the two operands; no memory, stack or flags contract
    // beyond what `asm!` assumes by default.
    unsafe {
        std::arch::asm!(
            "2:",
            "add {x}, 1",
            "add {x}, 1",
            "add {x}, 1",
            "add {x}, 1",
            "sub {n}, 4",
            "jnz 2b",
            x = inout(reg) x,
            n = inout(reg) left,
        );
    }
    let _ = left;
    x
}

/// CPU seconds of this process (Linux).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at the last ')'.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ is 100 on Linux
}

fn main() {
    #[cfg(target_arch = "x86_64")]
    for _ in 0..3 {
        let n = 4_000_000_000u64;
        let (c0, w0) = (cpu_seconds(), std::time::Instant::now());
        let x = dependent_adds(n);
        let (c1, wall) = (cpu_seconds(), w0.elapsed().as_secs_f64());
        match (c0, c1) {
            (Some(a), Some(b)) => println!(
                "{x} dependent adds: {:.2} s CPU, {wall:.2} s wall: {:.2} GHz",
                b - a,
                x as f64 / (b - a) / 1e9
            ),
            _ => println!(
                "{x} dependent adds in {wall:.2} s wall: {:.2} GHz (no CPU time)",
                x as f64 / wall / 1e9
            ),
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    println!("the clock measurement is written for x86-64 only");
}
