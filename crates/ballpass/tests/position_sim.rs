//! Position-domain spectra held to the simulator's truth: the ball-pass
//! line at `1 / (2 d_avg_true)` cycles/mm within 0.5 % at every speed, on
//! constant-speed runs and on runs whose speed varies (and turns around).
//! The randomized measurement over speeds 1–20 mm/s and many seeds is the
//! bench `position_line` (`cargo bench -p ballpass --bench position_line`).

use ballpass::analysis::position::position_spectra;
use ballpass::analysis::{AnalyzeSettings, Signal};
use ballpass::sim::{simulate, ProfilePlateau, SimSettings, SpeedProfile};

/// Runs the simulation and returns the measured deviation of the
/// friction's, the velocity error's and the optical signal's first line
/// from the truth, %.
fn deviation(settings: &SimSettings) -> [f64; 3] {
    let sim = simulate(settings).unwrap();
    let d = sim.truth.d_avg_mm;
    let p = position_spectra(&[sim.recording], d, &AnalyzeSettings::default()).unwrap();
    let truth = 1.0 / (2.0 * d);
    let dev = |s: Signal| {
        let l = p
            .line(s, 1)
            .unwrap_or_else(|| panic!("{s:?} line in {p:?}"));
        100.0 * (l.measured_per_mm - truth) / truth
    };
    [
        dev(Signal::Friction),
        dev(Signal::VelocityError),
        dev(Signal::Optical),
    ]
}

/// The default bench's friction pulses (0.2 N) put their fundamental only a
/// few dB above the rail roughness over 320 mm (the bench `position_line`
/// measures how far that lets the friction line wander); with 1 N pulses the
/// line stands clear and its position is what is tested.
fn strong_pulses(mut s: SimSettings) -> SimSettings {
    s.friction.pulse_amplitude_n = 1.0;
    s
}

fn check(what: &str, d: [f64; 3]) {
    // The bound: 0.5 % of 1/(2 d_avg_true).
    assert!(
        d.iter().all(|x| x.abs() < 0.5),
        "{what}: friction {:.3} %, v_e {:.3} %, optical {:.3} %",
        d[0],
        d[1],
        d[2]
    );
}

/// Constant speed at the ends of the range: the line sits at 1/(2 d_avg)
/// within 0.5 % (the bound) for friction and velocity error. The
/// duration gives 320 mm of travel (39 periods, a little more than one
/// circuit of the 36 balls: the local pitch of a few balls differs from
/// d_avg by up to ~0.5 %, the circuit's mean is d_avg exactly).
#[test]
fn the_line_stays_put_at_constant_speeds() {
    for (v, seed) in [(1.0, 11), (5.0, 12), (20.0, 13)] {
        let s = SimSettings {
            velocity_mm_s: v,
            duration_s: 320.0 / v + 2.0,
            seed,
            ..Default::default()
        };
        check(&format!("{v} mm/s"), deviation(&strong_pulses(s)));
    }
}

/// One run whose speed steps 3 → 9 → 15 → 6 mm/s, then turns around at
/// 12 mm/s: the time-domain line moves by a factor five, the
/// position-domain one of friction and optical stays within 0.5 % of the
/// truth.
#[test]
fn the_line_stays_put_when_the_speed_varies() {
    let speeds = [3.0, 9.0, 15.0, 6.0, -12.0];
    // 150 mm per plateau: 600 mm forward, then 150 mm back (one segment of
    // 16 periods, 130 mm, fits).
    let plateaus = speeds
        .into_iter()
        .map(|v: f64| ProfilePlateau {
            velocity_mm_s: v,
            duration_s: 150.0 / v.abs(),
        })
        .collect();
    let s = SimSettings {
        duration_s: speeds.iter().map(|v| 150.0 / v.abs()).sum::<f64>() + 3.0,
        seed: 7,
        profile: Some(SpeedProfile {
            plateaus,
            acceleration_mm_s2: 100.0,
        }),
        ..Default::default()
    };
    let d = deviation(&strong_pulses(s));
    // Friction and optical are locked to the passages: 0.5 %. The velocity
    // error is the stage's response to the friction, whose phase at the
    // ball-pass frequency changes with the speed, so a segment across a
    // speed change smears its line: within 2 % here (1.5 % measured),
    // 0.5 % at constant speed (above).
    assert!(
        d[0].abs() < 0.5 && d[2].abs() < 0.5 && d[1].abs() < 2.0,
        "friction {:.3} %, v_e {:.3} %, optical {:.3} %",
        d[0],
        d[1],
        d[2]
    );
}
