//! Text of the figures: the embedded font's metrics, and text drawn into
//! PNG bitmaps glyph by glyph at sub-pixel positions.
//!
//! `plotters` rasterises each glyph at the origin and then places it at the
//! caret position truncated to whole pixels, without the glyph's left side
//! bearing, so letters of a PNG label sit unevenly ("Fr e quency"). The
//! [`CrispText`] backend wraps the bitmap backend and draws text itself:
//! every glyph is outlined at its exact fractional position (advances and
//! kerning in `f32`), and its coverage is blended into the image. Lines,
//! shapes and everything else go to the wrapped backend unchanged.
//!
//! Sizes follow the SVG output: `plotters` writes a text of size `s` as
//! `font-size = s / 1.24` px, so [`CrispText`] draws an em of `s / 1.24` px,
//! with the same anchors as the SVG text (`dy` of 0.76 em for the top,
//! 0.5 ex for the centre).

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

/// The embedded font (DejaVu Sans, Bitstream Vera licence, see
/// `assets/fonts/DejaVuSans-LICENSE.txt`).
pub(crate) static FONT_TTF: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Ratio of `plotters`' text size to the em drawn (its SVG backend writes
/// `font-size = size / 1.24`).
pub(crate) const PLOTTERS_SIZE_PER_EM: f64 = 1.24;

/// The parsed embedded font, or `None` if it does not parse (then the
/// caller reports an error before drawing anything).
pub(crate) fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_TTF).ok())
        .as_ref()
}

/// The `ab_glyph` scale of an em of `em_px` pixels.
fn scale(f: &FontRef<'_>, em_px: f32) -> PxScale {
    let upem = f.units_per_em().unwrap_or(2048.0);
    PxScale::from(em_px * f.height_unscaled() / upem)
}

/// Advance width of `text` at an em of `em_px` pixels, with kerning.
pub(crate) fn text_width(text: &str, em_px: f64) -> f64 {
    let Some(f) = font() else {
        // a rough stand-in; `ensure_font` has already failed the drawing
        return 0.6 * em_px * text.chars().count() as f64;
    };
    let sf = f.as_scaled(scale(f, em_px as f32));
    let mut w = 0f32;
    let mut prev = None;
    for c in text.chars() {
        let id = sf.glyph_id(c);
        if let Some(p) = prev {
            w += sf.kern(p, id);
        }
        w += sf.h_advance(id);
        prev = Some(id);
    }
    f64::from(w)
}

/// A bitmap backend that draws text itself (see the module docs).
pub(crate) struct CrispText<B> {
    /// The wrapped backend.
    pub inner: B,
}

impl<B: DrawingBackend> DrawingBackend for CrispText<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let em = style.size() / PLOTTERS_SIZE_PER_EM;
        Ok((text_width(text, em).ceil() as u32, em.ceil() as u32))
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let color = style.color();
        let Some(f) = font() else {
            return self.inner.draw_text(text, style, pos);
        };
        if color.alpha == 0.0 || text.is_empty() {
            return Ok(());
        }
        let em = (style.size() / PLOTTERS_SIZE_PER_EM) as f32;
        let px = scale(f, em);
        let sf = f.as_scaled(px);
        let width = text_width(text, f64::from(em)) as f32;
        let x0 = match style.anchor().h_pos {
            HPos::Left => 0.0,
            HPos::Center => -width / 2.0,
            HPos::Right => -width,
        };
        // the SVG anchors: dy = 0.76em (top), 0.5ex (centre), -0.5ex (bottom)
        let upem = f.units_per_em().unwrap_or(2048.0);
        let x_height = f
            .outline(f.glyph_id('x'))
            .map_or(0.547, |o| (o.bounds.max.y - o.bounds.min.y).abs() / upem);
        let half_ex = 0.5 * x_height;
        let baseline = em
            * match style.anchor().v_pos {
                VPos::Top => 0.76,
                VPos::Center => half_ex,
                VPos::Bottom => -half_ex,
            };
        let trans = style.transform();
        let mut caret = x0;
        let mut prev = None;
        let mut cover: Vec<(i32, i32, f32)> = Vec::new();
        for c in text.chars() {
            let id = sf.glyph_id(c);
            if let Some(p) = prev {
                caret += sf.kern(p, id);
            }
            let glyph = id.with_scale_and_position(px, ab_glyph::point(caret, baseline));
            if let Some(o) = f.outline_glyph(glyph) {
                let b = o.px_bounds();
                o.draw(|gx, gy, v| {
                    cover.push((b.min.x as i32 + gx as i32, b.min.y as i32 + gy as i32, v));
                });
            }
            caret += sf.h_advance(id);
            prev = Some(id);
        }
        for (x, y, v) in cover {
            if v <= 0.0 {
                continue;
            }
            let (tx, ty) = trans.transform(x, y);
            self.inner.draw_pixel(
                (pos.0 + tx, pos.1 + ty),
                BackendColor {
                    alpha: color.alpha * f64::from(v.min(1.0)),
                    rgb: color.rgb,
                },
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Widths add up: a label is as wide as its parts (no kerning between
    /// these), and scale with the em.
    #[test]
    fn text_width_is_additive_and_scales() {
        let a = text_width("10", 16.0);
        let b = text_width("1", 16.0) + text_width("0", 16.0);
        assert!((a - b).abs() < 1e-3, "{a} {b}");
        let big = text_width("Frequency (Hz)", 32.0);
        let small = text_width("Frequency (Hz)", 16.0);
        assert!((big - 2.0 * small).abs() < 1e-2, "{big} {small}");
        // DejaVu Sans digits are 0.636 em wide
        assert!((text_width("0", 100.0) - 63.6).abs() < 0.2);
    }
}

#[cfg(test)]
mod spacing {
    use super::*;
    use plotters::prelude::*;

    /// Centres (column centroids of ink) of the strokes of `text` drawn on
    /// a white bitmap by `draw`, left to right.
    fn stems(draw: impl FnOnce(&mut [u8], (u32, u32))) -> Vec<f64> {
        let (w, h) = (400u32, 60u32);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        draw(&mut rgb, (w, h));
        let ink: Vec<f64> = (0..w as usize)
            .map(|x| {
                (0..h as usize)
                    .map(|y| 255.0 - f64::from(rgb[(y * w as usize + x) * 3]))
                    .sum()
            })
            .collect();
        let mut out = Vec::new();
        let mut x = 0;
        while x < ink.len() {
            if ink[x] > 0.0 {
                let start = x;
                while x < ink.len() && ink[x] > 0.0 {
                    x += 1;
                }
                let (m, s) =
                    (start..x).fold((0.0, 0.0), |(m, s), i| (m + i as f64 * ink[i], s + ink[i]));
                out.push(m / s);
            }
            x += 1;
        }
        out
    }

    fn spread(c: &[f64]) -> f64 {
        let d: Vec<f64> = c.windows(2).map(|w| w[1] - w[0]).collect();
        d.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - d.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Regression: PNG text had uneven letter spacing (each glyph placed at
    /// a truncated whole pixel). Eight identical strokes drawn by
    /// [`CrispText`] stand at equal distances, to 0.2 px (the
    /// anti-aliased coverage of each stroke differs slightly with its
    /// sub-pixel phase); plotters' own drawing is off by about a pixel.
    #[test]
    fn identical_letters_are_evenly_spaced() {
        assert!(font().is_some());
        plotters::style::register_font("ballpass-test", FontStyle::Normal, FONT_TTF)
            .map_err(|_| "font")
            .unwrap();
        let style =
            || TextStyle::from(("ballpass-test", 20.0 * PLOTTERS_SIZE_PER_EM)).color(&BLACK);
        let ours = stems(|buf, size| {
            let root = CrispText {
                inner: BitMapBackend::with_buffer(buf, size),
            }
            .into_drawing_area();
            root.draw(&Text::new("llllllll", (10, 20), style()))
                .unwrap();
            root.present().unwrap();
        });
        assert_eq!(ours.len(), 8, "{ours:?}");
        assert!(spread(&ours) < 0.2, "steps {ours:?}");
        // the advance of 'l' at a 20 px em
        let step = (ours[7] - ours[0]) / 7.0;
        assert!((step - text_width("l", 20.0)).abs() < 0.05, "{step}");
        let theirs = stems(|buf, size| {
            let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
            root.draw(&Text::new("llllllll", (10, 20), style()))
                .unwrap();
            root.present().unwrap();
        });
        assert!(spread(&theirs) > 0.5, "plotters' own spacing {theirs:?}");
    }
}
