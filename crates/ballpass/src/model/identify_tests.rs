use super::*;
use crate::recording::Channel;
use crate::sim::{simulate, SimSettings, StageSettings};

/// A stage the friction excites (5 Hz, ζ = 0.3, soft enough that the
/// velocity error stands above the encoder's quantisation): identified
/// from two minutes, its interval holding the truth.
#[test]
fn a_simulated_stage_is_identified() {
    let (fnat, zeta, mass) = (5.0, 0.3, 60.0);
    let wn = std::f64::consts::TAU * fnat;
    let mut s = SimSettings {
        duration_s: 120.0,
        stage: StageSettings {
            mass_kg: mass,
            kkp_n_per_m: mass * wn * wn,
            kkd_n_s_per_m: 2.0 * zeta * mass * wn,
        },
        ..SimSettings::default()
    };
    s.load_cell.time_constant_s = None;
    s.friction.roughness_length_mm = 0.3;
    let sim = simulate(&s).unwrap();
    let r = &sim.recording;
    let f = r.channel(Channel::Friction).unwrap();
    let p = r.channel(Channel::Position).unwrap();
    let v: Vec<f64> = ballpass_dsp::gradient(p, ballpass_dsp::Spacing::Uniform(1e-3))
        .unwrap()
        .iter()
        .map(|x| x - s.velocity_mm_s)
        .collect();
    let sp = StageSpectra::of(f, &v, 1000.0, nperseg_for(f.len(), 1000.0)).unwrap();
    let id = identify(&sp);
    let fe = id.natural_frequency_hz.unwrap();
    let ze = id.damping_ratio.unwrap();
    assert!(id.identified, "{id:#?}");
    assert!(
        (fe.value - fnat).abs() <= fe.ci95.max(0.05 * fnat),
        "{id:#?}"
    );
    assert!(
        (ze.value - zeta).abs() <= ze.ci95.max(0.2 * zeta),
        "{id:#?}"
    );
}

/// The stated intervals against a Monte-Carlo spread, on a system whose
/// response is known exactly: white friction (held over each sample)
/// through the PD stage discretised exactly, white noise on the
/// velocity error. Over 60 records the intervals must hold the truth
/// at about their nominal 95 % and have the width of the spread.
/// Tolerances: coverage ≥ 50/60 (at a true 95 % the chance of fewer is
/// 0.4 %; in a Monte-Carlo of this kind the estimator this replaced
/// held ζ on none), and the spread-to-stated ratio of f_n, ζ and the
/// peak gain within 0.7–1.45 (the ratio's own error over 60 records is
/// ~9 %; the replaced estimator's was 1.7 for ζ). The model here is
/// right (no chain, no load-cell high-pass), so the terms that widen the
/// intervals under misfit (the residuals' own correlation, the chain and
/// high-pass parameters) must not inflate them: stated/spread at most
/// 1.45 as well.
#[test]
fn intervals_match_a_monte_carlo_spread() {
    use crate::sim::rng::Rng;
    use crate::sim::PdStage;
    let (fs, secs, fnat, zeta, mass) = (1000.0, 32.0, 5.0, 0.3, 60.0);
    let wn = std::f64::consts::TAU * fnat;
    let settings = StageSettings {
        mass_kg: mass,
        kkp_n_per_m: mass * wn * wn,
        kkd_n_s_per_m: 2.0 * zeta * mass * wn,
    };
    let n = (fs * secs) as usize;
    let nperseg = nperseg_for(n, fs);
    let runs = 60;
    let truth = [fnat, zeta, 1e3 / settings.kkd_n_s_per_m];
    let mut est = Vec::new();
    for run in 0..runs {
        let mut rng = Rng::stream(13_000, run);
        let mut stage = PdStage::new(&settings, 1.0 / fs).unwrap();
        let mut f = Vec::with_capacity(n);
        let mut y = Vec::with_capacity(n);
        // Output noise: a random walk on the position, i.e. white
        // noise of ~0.05 mm/s on the centred-difference velocity
        // (coherence ~0.9 at the resonance, falling above it).
        let mut walk = 0.0;
        for _ in 0..n {
            let fk = 0.2 * rng.normal();
            y.push(stage.deviation_m() * 1e3 + walk);
            walk += 0.07 * rng.normal() / fs;
            stage.step(fk, 0.0);
            f.push(fk);
        }
        let sp = StageSpectra::of_signals(&f, &y, fs, 0.0, nperseg).unwrap();
        let id = identify(&sp);
        let (Some(a), Some(b), Some(c)) = (
            id.natural_frequency_hz,
            id.damping_ratio,
            id.peak_gain_mm_s_per_n,
        ) else {
            panic!("no fit on run {run}: {}", id.text);
        };
        est.push([a, b, c]);
    }
    for (k, name) in ["f_n", "ζ", "peak gain"].iter().enumerate() {
        let inside = est
            .iter()
            .filter(|e| (e[k].value - truth[k]).abs() <= e[k].ci95)
            .count();
        let mean = est.iter().map(|e| e[k].value).sum::<f64>() / runs as f64;
        let spread = (est.iter().map(|e| (e[k].value - mean).powi(2)).sum::<f64>()
            / (runs - 1) as f64)
            .sqrt();
        let stated = est.iter().map(|e| e[k].ci95 / Z95).sum::<f64>() / runs as f64;
        let ratio = spread / stated;
        eprintln!("{name}: {inside}/{runs} inside, spread/stated {ratio:.2}");
        assert!(
            inside >= 50,
            "{name}: {inside}/{runs} intervals hold the truth (spread/stated {ratio:.2}, mean {mean} vs {})",
            truth[k]
        );
        assert!(
            ratio <= 1.45,
            "{name}: spread {spread} against stated {stated} ({ratio:.2}): intervals too narrow"
        );
        assert!(
            stated / spread <= 1.45,
            "{name}: stated {stated} against spread {spread} ({:.2}): intervals inflated on a well-specified model",
            stated / spread
        );
    }
}

/// The jackknife over groups of one segment each is the classical one:
/// for the mean of the groups' values its variance is the sample
/// variance over the group count.
#[test]
fn the_jackknife_of_a_mean_is_the_classical_standard_error() {
    let xs = [3.0, 5.0, 4.0, 9.0, 1.0, 6.0, 2.0, 7.0];
    let g = xs.len();
    let nb = 4;
    let groups: Vec<SegmentGroup> = xs
        .iter()
        .map(|&x| SegmentGroup {
            p_ff: vec![x / g as f64; nb],
            p_vv: vec![1.0; nb],
            p_fv: vec![Complex64::new(0.0, 0.0); nb],
            segments: 1,
        })
        .collect();
    let mean = xs.iter().sum::<f64>() / g as f64;
    let s = StageSpectra {
        fs_hz: 100.0,
        freq_hz: (0..nb).map(|i| i as f64).collect(),
        p_ff: vec![mean; nb],
        p_vv: vec![g as f64; nb],
        p_fv: vec![Complex64::new(0.0, 0.0); nb],
        records: 1,
        n_d: g as f64,
        restored_tau_s: None,
        groups,
        encoder: None,
    };
    let se = super::jackknife::standard_errors(&s, [mean], |sp| Some([sp.p_ff[2]])).unwrap();
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (g - 1) as f64;
    let want = (var / g as f64).sqrt();
    assert!((se[0] - want).abs() <= 1e-12 * want, "{} vs {want}", se[0]);
}

/// The groups do not depend on how the record is handed over: fed in
/// pieces of uneven lengths (smaller and larger than a segment, as the
/// streamed analysis does) they equal the groups of the whole record bit
/// for bit, and they add up to the record's Welch estimate (to rounding:
/// 1e-12 relative, sums of 10 terms).
#[test]
fn segment_groups_are_the_same_in_pieces_and_add_up_to_the_welch_estimate() {
    use crate::stats::test_noise::gaussian;
    let (fs, n) = (100.0, 3000);
    let f = gaussian(n, 11);
    let v = gaussian(n, 12);
    let nperseg = nperseg_for(n, fs);
    let whole = StageSpectra::of(&f, &v, fs, nperseg).unwrap();
    // Segments of 512 at a hop of 256: (3000 − 512) / 256 + 1.
    assert_eq!(whole.groups.iter().map(|g| g.segments).sum::<usize>(), 10);
    let mut detrended = [f.clone(), v.iter().map(|x| x * 1e-3).collect::<Vec<f64>>()];
    for s in &mut detrended {
        ballpass_dsp::detrend_in_place(s, ballpass_dsp::DetrendType::Linear).unwrap();
    }
    let mut welch = super::grouped_welch(nperseg).unwrap();
    let mut at = 0;
    for (k, len) in [1usize, 90, 1000, 7, 400, 1500, 2]
        .iter()
        .cycle()
        .enumerate()
    {
        if at >= n || k > 100 {
            break;
        }
        let end = (at + len).min(n);
        welch
            .push(&[&detrended[0][at..end], &detrended[1][at..end]])
            .unwrap();
        at = end;
    }
    let pieces = StageSpectra::of_grouped(welch, fs, nperseg).unwrap();
    assert_eq!(pieces.groups, whole.groups);
    assert_eq!(pieces.p_fv, whole.p_fv);
    for i in 0..whole.groups[0].p_ff.len() {
        let sum: f64 = whole.groups.iter().filter_map(|g| g.p_ff.get(i)).sum();
        assert!(
            (sum - whole.p_ff[i]).abs() <= 1e-12 * whole.p_ff[i],
            "bin {i}"
        );
    }
}
