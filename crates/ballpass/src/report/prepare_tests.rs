use super::*;
use crate::report::spec::{Axis, Marker, Panel, Series};

fn fig_with(panel: Panel) -> Figure {
    Figure::new("t", "T").with_panel(panel)
}

#[test]
fn m4_keeps_every_column_extreme_and_bounds_size() {
    // 30 000 samples of a noisy sine with one spike
    let n = 30_000;
    let mut pts: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let x = i as f64 / n as f64;
            (
                x,
                (40.0 * x).sin() + 0.1 * ((i * 7919 % 101) as f64 / 101.0),
            )
        })
        .collect();
    pts[12_345].1 = 50.0;
    let cols = 800;
    let d = m4(&pts, 0.0, 1.0, cols);
    assert!(d.len() <= 4 * cols, "{} points", d.len());
    assert!(d.contains(&pts[12_345]), "spike lost");
    assert_eq!(d.first(), pts.first());
    assert_eq!(d.last(), pts.last());
    // every column's min and max survive exactly
    for c in 0..cols as i64 {
        let full: Vec<f64> = pts
            .iter()
            .filter(|p| column(p.0, 0.0, 1.0, cols) == c)
            .map(|p| p.1)
            .collect();
        let thin: Vec<f64> = d
            .iter()
            .filter(|p| column(p.0, 0.0, 1.0, cols) == c)
            .map(|p| p.1)
            .collect();
        let mx = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mn = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        assert_eq!(mx(&full), mx(&thin), "column {c}");
        assert_eq!(mn(&full), mn(&thin), "column {c}");
    }
    // order preserved
    assert!(d.windows(2).all(|w| w[1].0 >= w[0].0));
}

#[test]
fn m4_with_zoom_keeps_one_point_each_side() {
    let pts: Vec<(f64, f64)> = (0..10_000).map(|i| (i as f64, (i as f64).sin())).collect();
    let d = m4(&pts, 4000.0, 6000.0, 100);
    assert!(d.len() <= 4 * 100 + 2);
    assert!(d[0].0 < 4000.0 && d[d.len() - 1].0 > 6000.0);
}

#[test]
fn clipping_cuts_segments_at_the_edges() {
    let r = Rect {
        x0: 0.0,
        x1: 1.0,
        y0: 0.0,
        y1: 1.0,
    };
    let segs = clip_polyline(
        &[(-1.0, 0.5), (0.5, 0.5), (0.5, 2.0), (0.7, 0.5), (2.0, 0.5)],
        &r,
    );
    assert_eq!(segs.len(), 2, "{segs:?}");
    assert_eq!(segs[0], vec![(0.0, 0.5), (0.5, 0.5), (0.5, 1.0)]);
    let last = segs[1].last().copied().unwrap();
    assert_eq!(last, (1.0, 0.5));
}

#[test]
fn log_axis_drops_non_positive_points_with_a_warning() {
    let p = Panel::new(Axis::linear("f", "Hz"), Axis::log("P", "N²/Hz")).with_series(Series::line(
        "Pxx",
        vec![0.0, 1.0, 2.0, 3.0],
        vec![0.0, 1e-3, 1e-2, -1.0],
    ));
    let prep = prepare(&fig_with(p), 800).unwrap();
    assert_eq!(prep.warnings.len(), 1, "{:?}", prep.warnings);
    assert!(
        prep.warnings[0].contains("2 of 4 points have y <= 0"),
        "{}",
        prep.warnings[0]
    );
    let Shape::Lines { segments, .. } = &prep.panels[0].series[0].shapes[0] else {
        panic!("not a line")
    };
    assert_eq!(segments.len(), 1);
    assert_eq!(segments[0].len(), 2);
    // axis space of the log axis is log10
    assert!((segments[0][0].1 - (-3.0)).abs() < 1e-12);
}

#[test]
fn log_axis_with_nothing_positive_is_an_error() {
    let p = Panel::new(Axis::log("f", "Hz"), Axis::linear("P", "N")).with_series(Series::line(
        "s",
        vec![0.0, -1.0],
        vec![1.0, 2.0],
    ));
    let e = prepare(&fig_with(p), 800).unwrap_err().to_string();
    assert!(e.contains("no drawable data"), "{e}");
}

#[test]
fn bad_ranges_and_lengths_are_errors() {
    let p = Panel::new(
        Axis::log("f", "Hz").with_range(0.0, 10.0),
        Axis::linear("P", "N"),
    )
    .with_series(Series::line("s", vec![1.0], vec![1.0]));
    assert!(prepare(&fig_with(p), 800)
        .unwrap_err()
        .to_string()
        .contains("must be positive"));
    let p = Panel::new(
        Axis::linear("t", "s").with_range(2.0, 1.0),
        Axis::linear("P", "N"),
    )
    .with_series(Series::line("s", vec![1.0], vec![1.0]));
    assert!(prepare(&fig_with(p), 800)
        .unwrap_err()
        .to_string()
        .contains("low < high"));
    let p = Panel::new(Axis::linear("t", "s"), Axis::linear("P", "N")).with_series(Series::line(
        "s",
        vec![1.0, 2.0],
        vec![1.0],
    ));
    let e = prepare(&fig_with(p), 800).unwrap_err().to_string();
    assert!(
        e.contains("x has 2 values but y has 1") && e.contains("series 's'"),
        "{e}"
    );
    let p = Panel::new(Axis::linear("t", "s"), Axis::linear("P", "N")).with_series(
        Series::error_bars("s", vec![1.0, 2.0], vec![1.0, 1.0], vec![0.1, -0.1]),
    );
    assert!(prepare(&fig_with(p), 800)
        .unwrap_err()
        .to_string()
        .contains(">= 0"));
    let bad_id = Figure::new("a/b", "x")
        .with_panel(Panel::new(Axis::linear("t", "s"), Axis::linear("y", "")));
    assert!(prepare(&bad_id, 800).is_err());
    assert!(prepare(&Figure::new("a", "x"), 800)
        .unwrap_err()
        .to_string()
        .contains("no panels"));
}

#[test]
fn markers_outside_the_range_are_not_drawn() {
    let p = Panel::new(
        Axis::linear("τ", "s").with_range(-3.0, 3.0),
        Axis::linear("R", ""),
    )
    .with_series(Series::uniform("R", -10.0, 0.01, vec![0.5; 2001]))
    .with_vlines(Marker::multiples(0.9, -10.0, 10.0, "τc", false));
    let prep = prepare(&fig_with(p), 800).unwrap();
    // ±0.9, ±1.8, ±2.7
    assert_eq!(prep.panels[0].vlines.len(), 6);
}

#[test]
fn highlighted_series_is_drawn_last_and_thicker() {
    let p = Panel::new(Axis::linear("f", "Hz"), Axis::log("P", "N²/Hz"))
        .with_series(Series::line("b1", vec![1.0, 2.0], vec![1.0, 2.0]))
        .with_series(Series::line("b4", vec![1.0, 2.0], vec![3.0, 4.0]).highlighted())
        .with_series(Series::line("b5", vec![1.0, 2.0], vec![1.0, 2.0]));
    let prep = prepare(&fig_with(p), 800).unwrap();
    let s = &prep.panels[0].series;
    assert_eq!(s[2].name, "b4");
    assert!(s[2].stroke_px > s[0].stroke_px);
    // colours follow the declared order, not the drawing order
    assert_eq!(s[2].color, Rgb::palette(1));
    assert_eq!(s[1].color, Rgb::palette(2));
}
