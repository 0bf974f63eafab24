//! Prints the simulated velocity-error standard deviation against tracking
//! velocity (the simulator's counterpart of thesis Fig. 29), averaged over
//! repeats: `cargo run --release -p ballpass --example sim_sweep [repeats]`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: u64 = std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(3);
    println!("v_mm_s  ve_std_um_s  ve_true_std_um_s  passage_rate/f_c");
    for v in 1..=20 {
        let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
        for seed in 0..repeats {
            let s = ballpass::sim::SimSettings {
                velocity_mm_s: f64::from(v),
                seed,
                ..Default::default()
            };
            let t = ballpass::sim::simulate(&s)?.truth;
            a += t.velocity_error_std_mm_s * 1e3;
            b += t.velocity_error_true_std_mm_s * 1e3;
            c += t.passage_rate_hz.unwrap_or(f64::NAN) / t.f_c_hz;
        }
        let n = repeats as f64;
        println!("{v:>6} {:>12.1} {:>17.1} {:>17.4}", a / n, b / n, c / n);
    }
    Ok(())
}
