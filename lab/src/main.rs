//! oit-lab: placeholder until the lab issue lands.
fn main() {
    println!("oit-lab: not yet implemented");
}
