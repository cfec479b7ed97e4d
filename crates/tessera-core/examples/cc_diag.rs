use std::path::Path;
use tessera_core::catmull_clark::*;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let model = load_surface(Path::new(&path)).unwrap();
    let p: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0);
    let n: usize = std::env::args()
        .nth(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(6);
    for j in (0..n).rev() {
        let mut line = String::new();
        for i in 0..n {
            let b = [
                i as f64 / n as f64,
                (i + 1) as f64 / n as f64,
                j as f64 / n as f64,
                (j + 1) as f64 / n as f64,
            ];
            line += &format!("{:9.2e}", adaptive::flatness_bound(&model, p, b));
        }
        println!("{line}");
    }
}
