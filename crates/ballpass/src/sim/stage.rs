//! The air-bearing stage under PD control (thesis Fig. 40, Eqs. 6.1–6.6),
//! integrated exactly by zero-order-hold discretisation.
//!
//! Sign convention: friction *opposes* motion. With the ramp reference
//! `r = V t` and the tracking deviation `y = x - r`,
//!
//! ```text
//! m x'' = K K_P (r - x) + K K_D (r' - x') - f_f        (f_f > 0 for x' > 0)
//! m y'' = -K K_P y - K K_D y' - f_f - m r''
//! ```
//!
//! so the velocity error `y' = x' - V` responds to the friction force with
//! `-G_vf(s)`, `G_vf(s) = s / (m s^2 + K K_D s + K K_P)` (Eq. 6.6), and a
//! constant friction `F_c` leaves the stage `F_c / (K K_P)` behind the
//! reference with no velocity error (docs/methods.md §3). The thesis' Eq. 6.6 is
//! written for friction entering with `+`; the load cell of the bench reads
//! the force the rail exerts on the truck, which is `+f_f`.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Parameters of the stage model.
///
/// The defaults are assumptions (the thesis gives no stage parameters): the
/// natural frequency `sqrt(K K_P / m)` is put at the ball-pass frequency at
/// 9 mm/s (1.1096 Hz) with damping ratio 0.35, so that the velocity-error
/// standard deviation peaks at 9 mm/s (thesis Fig. 29) and friction and
/// velocity error share a zero-lag correlation peak there (thesis Fig. 58;
/// `G_vf` is real at `omega_n`). The effective mass sets the force-to-velocity
/// scale: with 240 kg, friction fluctuations of 0.2 N on a 3 N Coulomb level
/// give a velocity error of order 100 µm/s, while the sticking bearing's
/// spikes (up to 27 N) leave the stage moving (velocity-error std about
/// 0.5 mm/s at 20 mm/s). With a realistic carriage mass (10–15 kg) at the
/// same natural frequency, 0.01 N would already give 100 µm/s and the
/// sticking spikes would stall the stage, against thesis Fig. 66; with a
/// realistically stiff servo (tens of Hz), no friction of a few newtons
/// could produce Fig. 29's 110 µm/s. So 240 kg is an effective model mass
/// for a PD cartoon of the real loop, not the carriage's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StageSettings {
    /// Effective moving mass `m`, kg.
    pub mass_kg: f64,
    /// Proportional gain times motor constant `K K_P`, N/m.
    pub kkp_n_per_m: f64,
    /// Derivative gain times motor constant `K K_D`, N·s/m.
    pub kkd_n_s_per_m: f64,
}

impl Default for StageSettings {
    fn default() -> Self {
        let mass_kg = 240.0;
        let omega_n = std::f64::consts::TAU * DEFAULT_NATURAL_FREQUENCY_HZ;
        Self {
            mass_kg,
            kkp_n_per_m: mass_kg * omega_n * omega_n,
            kkd_n_s_per_m: 2.0 * DEFAULT_DAMPING_RATIO * mass_kg * omega_n,
        }
    }
}

/// Default natural frequency: the ball-pass frequency of an SR25W at 9 mm/s, Hz.
pub const DEFAULT_NATURAL_FREQUENCY_HZ: f64 = 9.0 / (2.0 * (4.0 + 2.0 / 36.0));
/// Default damping ratio of the PD loop.
pub const DEFAULT_DAMPING_RATIO: f64 = 0.35;

impl StageSettings {
    /// Natural frequency `omega_n = sqrt(K K_P / m)`, rad/s.
    pub fn omega_n_rad_s(&self) -> f64 {
        (self.kkp_n_per_m / self.mass_kg).sqrt()
    }

    /// Damping ratio `zeta = K K_D / (2 sqrt(m K K_P))` (docs/methods.md §3).
    pub fn damping_ratio(&self) -> f64 {
        self.kkd_n_s_per_m / (2.0 * (self.mass_kg * self.kkp_n_per_m).sqrt())
    }

    /// Steady position lag behind the reference under a constant friction
    /// `F_c`: `F_c / (K K_P)`, m.
    pub fn steady_offset_m(&self, friction_n: f64) -> f64 {
        friction_n / self.kkp_n_per_m
    }

    /// `G_vf(j omega) = j omega / (K K_P - m omega^2 + j omega K K_D)` (Eq. 6.6),
    /// as (re, im), in (m/s)/N.
    pub fn g_vf(&self, omega_rad_s: f64) -> (f64, f64) {
        let (a, b) = (
            self.kkp_n_per_m - self.mass_kg * omega_rad_s * omega_rad_s,
            omega_rad_s * self.kkd_n_s_per_m,
        );
        // j w / (a + j b) = j w (a - j b) / (a^2 + b^2) = (w b + j w a) / |.|^2
        let d = a * a + b * b;
        (omega_rad_s * b / d, omega_rad_s * a / d)
    }

    /// Checks that all three parameters are positive and finite.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the parameter.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("stage mass_kg", self.mass_kg),
            ("stage kkp_n_per_m", self.kkp_n_per_m),
            ("stage kkd_n_s_per_m", self.kkd_n_s_per_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::setting(
                    name,
                    format!("must be a positive number, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// Matrix exponential of a small dense `n x n` matrix (row-major), by
/// scaling and squaring with a Taylor series.
///
/// The matrix is scaled by `2^-s` until its 1-norm is below 1/2, the series
/// is summed to 20 terms (truncation error below `0.5^21 / 21! ≈ 1e-26`
/// relative), then squared `s` times.
///
/// # Panics
/// If `a.len() != n * n` (an internal contract).
pub fn expm(a: &[f64], n: usize) -> Vec<f64> {
    assert_eq!(a.len(), n * n, "expm: matrix is not {n} x {n}");
    let norm1 = (0..n)
        .map(|j| (0..n).map(|i| a[i * n + j].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut s = 0u32;
    let mut scale = 1.0;
    while norm1 * scale > 0.5 {
        scale *= 0.5;
        s += 1;
    }
    let a_s: Vec<f64> = a.iter().map(|x| x * scale).collect();
    let mut result = identity(n);
    let mut term = identity(n);
    for k in 1..=20 {
        term = matmul(&term, &a_s, n);
        let inv_k = 1.0 / f64::from(k);
        term.iter_mut().for_each(|t| *t *= inv_k);
        result.iter_mut().zip(&term).for_each(|(r, t)| *r += t);
    }
    for _ in 0..s {
        result = matmul(&result, &result, n);
    }
    result
}

fn identity(n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    (0..n).for_each(|i| m[i * n + i] = 1.0);
    m
}

fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            for j in 0..n {
                c[i * n + j] += aik * b[k * n + j];
            }
        }
    }
    c
}

/// Exact zero-order-hold discretisation of `x' = A x + b u` over `dt`:
/// `x[k+1] = A_d x[k] + b_d u[k]` with
///
/// ```text
/// expm([[A, b], [0, 0]] dt) = [[A_d, b_d], [0, 1]]
/// ```
///
/// Returns `(A_d, b_d)` for a 2-state single-input system.
pub fn zoh2(a: [[f64; 2]; 2], b: [f64; 2], dt: f64) -> ([[f64; 2]; 2], [f64; 2]) {
    let m = [
        a[0][0] * dt,
        a[0][1] * dt,
        b[0] * dt,
        a[1][0] * dt,
        a[1][1] * dt,
        b[1] * dt,
        0.0,
        0.0,
        0.0,
    ];
    let e = expm(&m, 3);
    ([[e[0], e[1]], [e[3], e[4]]], [e[2], e[5]])
}

/// The PD-controlled stage, advanced one fixed step at a time.
///
/// State: tracking deviation `y = x - r` (m) and velocity error `y' = x' - r'`
/// (m/s). Each step holds the disturbance force constant (zero-order hold),
/// which is exact for piecewise-constant forces.
#[derive(Debug, Clone)]
pub struct PdStage {
    ad: [[f64; 2]; 2],
    bd: [f64; 2],
    mass_kg: f64,
    y_m: f64,
    ydot_m_s: f64,
}

impl PdStage {
    /// Discretises the stage for a step of `dt_s`, starting on the reference
    /// (`y = 0`, `y' = 0`).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for bad parameters or a non-positive step.
    pub fn new(settings: &StageSettings, dt_s: f64) -> Result<Self> {
        settings.validate()?;
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::setting(
                "time step",
                format!("must be a positive number of s, got {dt_s}"),
            ));
        }
        let m = settings.mass_kg;
        let a = [
            [0.0, 1.0],
            [-settings.kkp_n_per_m / m, -settings.kkd_n_s_per_m / m],
        ];
        let (ad, bd) = zoh2(a, [0.0, 1.0 / m], dt_s);
        Ok(Self {
            ad,
            bd,
            mass_kg: m,
            y_m: 0.0,
            ydot_m_s: 0.0,
        })
    }

    /// Sets the state: deviation from the reference (m) and velocity error (m/s).
    pub fn set_state(&mut self, y_m: f64, ydot_m_s: f64) {
        self.y_m = y_m;
        self.ydot_m_s = ydot_m_s;
    }

    /// Deviation from the reference `y = x - r`, m.
    pub fn deviation_m(&self) -> f64 {
        self.y_m
    }

    /// Velocity error `x' - r'`, m/s.
    pub fn velocity_error_m_s(&self) -> f64 {
        self.ydot_m_s
    }

    /// Advances one step with friction `friction_n` (opposing positive
    /// motion, so it enters with `-`) and reference acceleration
    /// `ref_accel_m_s2`, both held over the step.
    pub fn step(&mut self, friction_n: f64, ref_accel_m_s2: f64) {
        let u = -friction_n - self.mass_kg * ref_accel_m_s2;
        let (y, v) = (self.y_m, self.ydot_m_s);
        self.y_m = self.ad[0][0] * y + self.ad[0][1] * v + self.bd[0] * u;
        self.ydot_m_s = self.ad[1][0] * y + self.ad[1][1] * v + self.bd[1] * u;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    /// expm of a diagonal matrix and of a rotation generator against their
    /// closed forms; 1e-13 relative is a few ulps after ~10 squarings.
    #[test]
    fn expm_matches_closed_forms() {
        let e = expm(&[1.5, 0.0, 0.0, -3.0], 2);
        assert!(close(e[0], 1.5f64.exp(), 1e-13) && close(e[3], (-3.0f64).exp(), 1e-13));
        assert!(e[1].abs() < 1e-15 && e[2].abs() < 1e-15);
        let w = 7.3;
        let e = expm(&[0.0, w, -w, 0.0], 2);
        assert!(close(e[0], w.cos(), 1e-13) && close(e[1], w.sin(), 1e-13));
        assert!(close(e[2], -w.sin(), 1e-13) && close(e[3], w.cos(), 1e-13));
        // Nilpotent: expm([[0,1,0],[0,0,1],[0,0,0]] t) = [[1,t,t^2/2],[0,1,t],[0,0,1]].
        let t = 2.5;
        let e = expm(&[0.0, t, 0.0, 0.0, 0.0, t, 0.0, 0.0, 0.0], 3);
        assert!(close(e[1], t, 1e-14) && close(e[2], t * t / 2.0, 1e-14) && close(e[5], t, 1e-14));
    }

    /// ZOH of an underdamped oscillator against the closed-form step
    /// response: y(dt) for a unit force from rest is
    /// (1/k)(1 - e^{-zeta wn dt}(cos wd dt + zeta wn / wd sin wd dt)).
    #[test]
    fn zoh_matches_closed_form_step_response() {
        let (m, k, c): (f64, f64, f64) = (2.0, 50.0, 3.0);
        let wn = (k / m).sqrt();
        let zeta = c / (2.0 * (m * k).sqrt());
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        for dt in [1e-4, 0.01, 0.3, 2.0] {
            let (_, bd) = zoh2([[0.0, 1.0], [-k / m, -c / m]], [0.0, 1.0 / m], dt);
            let s = (-zeta * wn * dt).exp();
            let y = (1.0 - s * ((wd * dt).cos() + zeta * wn / wd * (wd * dt).sin())) / k;
            let v = s * wn * wn / wd * (wd * dt).sin() / k;
            // 1e-12 relative: expm is accurate to ~1e-15; the closed form loses a
            // few digits to cancellation at the smallest dt.
            assert!(close(bd[0], y, 1e-10), "dt {dt}: {} vs {y}", bd[0]);
            assert!(close(bd[1], v, 1e-12), "dt {dt}: {} vs {v}", bd[1]);
        }
    }

    /// A constant friction settles to y = -F_c / (K K_P) with zero velocity
    /// error (docs/methods.md §3). After 60 s (30 time constants 1/(zeta wn)) the
    /// transient is below e^-30; tolerance 1e-9 relative.
    #[test]
    fn constant_friction_gives_offset_and_no_velocity_error() {
        let s = StageSettings::default();
        let mut st = PdStage::new(&s, 1e-3).unwrap();
        for _ in 0..60_000 {
            st.step(3.0, 0.0);
        }
        let off = s.steady_offset_m(3.0);
        assert!(
            close(st.deviation_m(), -off, 1e-9),
            "{} vs {}",
            st.deviation_m(),
            -off
        );
        assert!(st.velocity_error_m_s().abs() < 1e-12 * off);
    }
}
