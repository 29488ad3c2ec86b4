fn main() {
    println!("genpath {}", env!("CARGO_PKG_VERSION"));
}
