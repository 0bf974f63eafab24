//! The balls of one circuit: random spacings, and the sequence of ball
//! passages in terms of the distance the balls have travelled.
//!
//! The balls move at half the stage velocity relative to the truck, so after
//! the stage has travelled `Δx` every ball has advanced `Δx / 2` along the
//! circuit. Ball passages are therefore fixed points on that "ball travel"
//! axis `s = Δx / 2` (mm): ball `k` enters the loaded zone when
//! `s = e_k + lap L`, with `L = N_B d + d_ext = N_B d_avg` the circuit length,
//! and passes the optical sensor `sensor_offset_mm` later.

use super::rng::Rng;
use crate::bearing::Geometry;

/// One ball passage on the ball-travel axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Passage {
    /// Ball travel `s` at which the ball centre enters the loaded zone, mm.
    pub travel_mm: f64,
    /// Which ball (0-based, in circuit order).
    pub ball: usize,
}

/// Balls of one circuit, with the free space shared at random.
#[derive(Debug, Clone, PartialEq)]
pub struct Circuit {
    /// Centre-to-centre spacing from ball `k` to ball `k+1` (cyclic), mm.
    /// Each is `d + g_k` with the gaps `g_k` a uniform random split of `d_ext`.
    pub spacings_mm: Vec<f64>,
    /// Ball travel at which ball 0 first reaches the loaded zone, mm, in `[0, L)`.
    pub first_entry_mm: f64,
}

impl Circuit {
    /// Draws a circuit: gaps `g_k = d_ext E_k / sum E` with `E_k` standard
    /// exponentials (a flat Dirichlet: the uniform-spacings split of `d_ext`,
    /// so a single gap ranges over `0..d_ext`, docs/methods.md §1), and a uniform
    /// random position of the circuit.
    pub fn draw(geometry: &Geometry, rng: &mut Rng) -> Self {
        let n = geometry.balls_in_race as usize;
        let e: Vec<f64> = (0..n).map(|_| rng.exponential()).collect();
        let sum: f64 = e.iter().sum();
        let spacings_mm: Vec<f64> = e
            .iter()
            .map(|x| geometry.ball_diameter_mm + geometry.free_space_mm * x / sum)
            .collect();
        let length = geometry.d_avg_mm() * n as f64;
        Self {
            spacings_mm,
            first_entry_mm: rng.uniform() * length,
        }
    }

    /// Circuit length `L = sum of spacings = N_B d_avg`, mm.
    pub fn length_mm(&self) -> f64 {
        self.spacings_mm.iter().sum()
    }

    /// All loaded-zone entries with ball travel in `[from_mm, to_mm]`, in order.
    ///
    /// The entry of ball `k` is `first_entry + sum_{i<k} spacing_i + lap L`;
    /// balls enter in the order 0, 1, 2, ... because each follows the one
    /// before it by one spacing.
    pub fn passages(&self, from_mm: f64, to_mm: f64) -> Vec<Passage> {
        let n = self.spacings_mm.len();
        let length = self.length_mm();
        let mut offsets = Vec::with_capacity(n);
        let mut acc = self.first_entry_mm;
        for s in &self.spacings_mm {
            offsets.push(acc);
            acc += s;
        }
        let first_lap = ((from_mm - acc) / length).floor() as i64;
        let mut out = Vec::new();
        let mut lap = first_lap;
        loop {
            let base = lap as f64 * length;
            if base + self.first_entry_mm > to_mm {
                break;
            }
            for (ball, off) in offsets.iter().enumerate() {
                let t = base + off;
                if t >= from_mm && t <= to_mm {
                    out.push(Passage { travel_mm: t, ball });
                }
            }
            lap += 1;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bearing::lookup;

    #[test]
    fn spacings_share_the_free_space_and_passages_repeat_per_lap() {
        let g = lookup("sr25w").unwrap().geometry;
        let mut rng = Rng::new(3);
        let c = Circuit::draw(&g, &mut rng);
        assert_eq!(c.spacings_mm.len(), 36);
        // Sum of spacings is N_B d + d_ext = 146 mm up to rounding of 36 additions.
        assert!((c.length_mm() - 146.0).abs() < 1e-12);
        assert!(c.spacings_mm.iter().all(|&s| (4.0..=6.0).contains(&s)));
        let p = c.passages(-200.0, 400.0);
        assert!(p.windows(2).all(|w| w[1].travel_mm > w[0].travel_mm));
        // 600 mm of ball travel holds 600 / d_avg = 147.9 entries: 147 or 148.
        assert!((147..=148).contains(&p.len()), "{}", p.len());
        // Same ball one lap later.
        assert_eq!(p[0].ball, p[36].ball);
        assert!((p[36].travel_mm - p[0].travel_mm - 146.0).abs() < 1e-9);
        // Consecutive entries are one spacing apart.
        let k = p[0].ball;
        assert!((p[1].travel_mm - p[0].travel_mm - c.spacings_mm[k]).abs() < 1e-12);
    }
}
