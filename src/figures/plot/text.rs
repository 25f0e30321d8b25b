//! Labels with sub- and superscripts, drawn span by span.
//!
//! A label is written in a small markup: `_x` or `_{xy}` for a subscript, `^x` or `^{xy}` for
//! a superscript (`K_{PL}`, `λ_s`, `W/W_0`, `A*/λ_s^2`, `10^{−4}`); everything else is drawn
//! as written (`\_` and `\^` for the characters themselves, see [`escape`]). Subscripts and
//! superscripts are drawn smaller and shifted, so no markup reaches the image. Characters of
//! the mathematical alphanumeric block (𝒦) are drawn in the embedded math font, which the
//! text font lacks.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontTransform;

/// Where a span sits relative to the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Base,
    Sub,
    Sup,
}

/// One run of text at one level.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Span {
    pub text: String,
    pub level: Level,
}

/// Family name of the text font (registered by the plot module).
pub const TEXT_FAMILY: &str = "sans-serif";
/// Family name of the math font (for 𝒦 and other mathematical alphanumerics).
pub const MATH_FAMILY: &str = "DejaVu Math TeX Gyre";

/// Size of sub- and superscripts relative to the line.
const SCRIPT_SCALE: f64 = 0.7;

/// Split `markup` into spans (see the module documentation).
pub fn parse(markup: &str) -> Vec<Span> {
    let mut out: Vec<Span> = Vec::new();
    let push = |text: String, level: Level, out: &mut Vec<Span>| {
        if text.is_empty() {
            return;
        }
        match out.last_mut() {
            Some(last) if last.level == level => last.text.push_str(&text),
            _ => out.push(Span { text, level }),
        }
    };
    let chars: Vec<char> = markup.chars().collect();
    let mut i = 0;
    let mut base = String::new();
    while i < chars.len() {
        let c = chars[i];
        // `\_` and `\^`: the character itself.
        if c == '\\' && matches!(chars.get(i + 1), Some('_' | '^')) {
            base.push(chars[i + 1]);
            i += 2;
            continue;
        }
        let level = match c {
            '_' => Level::Sub,
            '^' => Level::Sup,
            _ => Level::Base,
        };
        if level == Level::Base || i + 1 == chars.len() {
            base.push(c);
            i += 1;
            continue;
        }
        push(std::mem::take(&mut base), Level::Base, &mut out);
        let script: String = if chars[i + 1] == '{' {
            let close = chars[i + 2..]
                .iter()
                .position(|&c| c == '}')
                .map_or(chars.len(), |p| i + 2 + p);
            let s = chars[i + 2..close.min(chars.len())].iter().collect();
            i = close + 1;
            s
        } else {
            i += 2;
            chars[i - 1].to_string()
        };
        push(script, level, &mut out);
    }
    push(base, Level::Base, &mut out);
    out
}

/// `s` as literal text in a label (identifiers with underscores, e.g. study names).
pub fn escape(s: &str) -> String {
    s.replace('_', "\\_").replace('^', "\\^")
}

/// The text as drawn, without markup (for tests).
pub fn plain(markup: &str) -> String {
    parse(markup).into_iter().map(|s| s.text).collect()
}

/// `c` mapped from `from` to the character at the same place in `to`, if any.
fn mapped(c: char, from: &str, to: &str) -> Option<char> {
    from.chars()
        .position(|f| f == c)
        .and_then(|i| to.chars().nth(i))
}

/// Unicode subscript of `c`, where Unicode has one.
fn subscript_char(c: char) -> Option<char> {
    mapped(
        c,
        "0123456789+−-=()aehijklmnoprstuvx",
        "₀₁₂₃₄₅₆₇₈₉₊₋₋₌₍₎ₐₑₕᵢⱼₖₗₘₙₒₚᵣₛₜᵤᵥₓ",
    )
}

/// Unicode superscript of `c`, where Unicode has one.
fn superscript_char(c: char) -> Option<char> {
    mapped(c, "0123456789+−-=()in*", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻⁻⁼⁽⁾ⁱⁿ*")
}

/// The label on one line of plain Unicode (for data files): scripts as Unicode sub- and
/// superscript characters where every character has one (`W/W₀`, `λₛ²`), else written
/// `_PL` / `^x` (`K_PL`).
pub fn flat(markup: &str) -> String {
    let mut out = String::new();
    for span in parse(markup) {
        let (map, mark): (fn(char) -> Option<char>, char) = match span.level {
            Level::Base => {
                out.push_str(&span.text);
                continue;
            }
            Level::Sub => (subscript_char, '_'),
            Level::Sup => (superscript_char, '^'),
        };
        match span.text.chars().map(map).collect::<Option<String>>() {
            Some(s) => out.push_str(&s),
            None => {
                out.push(mark);
                out.push_str(&span.text);
            }
        }
    }
    out
}

/// Whether `c` is drawn in the math font.
fn is_math(c: char) -> bool {
    ('\u{1D400}'..='\u{1D7FF}').contains(&c)
}

/// Runs of `text` by font family.
fn runs(text: &str) -> Vec<(&'static str, String)> {
    let mut out: Vec<(&'static str, String)> = Vec::new();
    for c in text.chars() {
        let family = if is_math(c) { MATH_FAMILY } else { TEXT_FAMILY };
        match out.last_mut() {
            Some((f, s)) if *f == family => s.push(c),
            _ => out.push((family, c.to_string())),
        }
    }
    out
}

/// How a label sits on its anchor point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// The anchor is the start of the text.
    Start,
    /// The anchor is the middle of the text.
    Middle,
    /// The anchor is the end of the text.
    End,
}

/// Text size in pixels, colour, and whether the text reads upwards (a y-axis label).
#[derive(Clone, Copy, Debug)]
pub struct TextLook {
    pub size: f64,
    pub color: RGBColor,
    pub upwards: bool,
}

impl TextLook {
    pub fn new(size: f64) -> Self {
        TextLook {
            size,
            color: BLACK,
            upwards: false,
        }
    }
}

/// (family, text, size, offset of its top along the line's normal) of every run.
fn layout(markup: &str, size: f64) -> Vec<(&'static str, String, f64, f64)> {
    let mut out = Vec::new();
    for span in parse(markup) {
        let (s, top) = match span.level {
            Level::Base => (size, 0.0),
            // Baseline of a script a fifth of the size below (sub) or a third above (sup)
            // the line's baseline, which sits half a size below the top (ab_glyph layout).
            Level::Sub => {
                let s = size * SCRIPT_SCALE;
                (s, 0.5 * size + 0.2 * size - 0.5 * s)
            }
            Level::Sup => {
                let s = size * SCRIPT_SCALE;
                (s, 0.5 * size - 0.35 * size - 0.5 * s)
            }
        };
        for (family, text) in runs(&span.text) {
            out.push((family, text, s, top));
        }
    }
    out
}

fn style(family: &'static str, size: f64, look: &TextLook) -> TextStyle<'static> {
    let mut st = TextStyle {
        font: (family, size).into_font(),
        color: look.color.to_backend_color(),
        pos: Pos::new(HPos::Left, VPos::Top),
    };
    if look.upwards {
        st = st.transform(FontTransform::Rotate270);
    }
    st
}

/// The embedded text font's bytes.
static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
/// The embedded math font (DejaVu Math TeX Gyre, same licence), for the few mathematical
/// letters the text font lacks (𝒦).
static MATH_FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuMathTeXGyre.ttf");

/// Register the embedded fonts under the families the text module asks for.
pub(super) fn ensure_font() -> anyhow::Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(TEXT_FAMILY, FontStyle::Normal, FONT).is_ok()
            && plotters::style::register_font(MATH_FAMILY, FontStyle::Normal, MATH_FONT).is_ok()
    });
    anyhow::ensure!(ok, "the embedded fonts could not be registered");
    Ok(())
}

/// The embedded font of `family`.
fn font_of(family: &str) -> ab_glyph::FontRef<'static> {
    let bytes = if family == MATH_FAMILY {
        MATH_FONT
    } else {
        FONT
    };
    ab_glyph::FontRef::try_from_slice(bytes).expect("the embedded fonts parse")
}

/// Where each glyph of `text` (one font, `size` pixels) starts, relative to the run's start:
/// its pen position (advances and kerning) plus its left side bearing, which plotters leaves
/// out when it draws a glyph (so drawn as one string, "128" reads "12 8"); and the run's
/// advance.
fn glyph_starts(family: &str, text: &str, size: f64) -> (Vec<(char, i32)>, f32) {
    use ab_glyph::{Font, ScaleFont};
    let font = font_of(family);
    let scaled = font.as_scaled(size as f32);
    let (mut pen, mut prev) = (0f32, None);
    let mut out = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            pen += scaled.kern(p, id);
        }
        let bearing = scaled
            .outline_glyph(scaled.scaled_glyph(c))
            .map_or(0.0, |g| g.px_bounds().min.x);
        out.push((c, (pen + bearing).round() as i32));
        pen += scaled.h_advance(id);
        prev = Some(id);
    }
    (out, pen)
}

thread_local! {
    static GLYPHWISE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// While alive, text is drawn glyph by glyph ([`glyph_starts`]): for raster images, which
/// plotters rasterises itself. An SVG keeps whole strings, laid out by the reader's renderer.
pub struct Glyphwise(bool);

impl Glyphwise {
    pub fn on() -> Self {
        Glyphwise(GLYPHWISE.with(|g| g.replace(true)))
    }
}

impl Drop for Glyphwise {
    fn drop(&mut self) {
        GLYPHWISE.with(|g| g.set(self.0));
    }
}

fn glyphwise() -> bool {
    GLYPHWISE.with(|g| g.get())
}

/// Width in pixels of `markup` drawn at `size`.
pub fn width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, markup: &str, size: f64) -> i32 {
    let runs = layout(markup, size);
    if glyphwise() {
        return runs
            .iter()
            .map(|(family, text, s, _)| glyph_starts(family, text, *s).1)
            .sum::<f32>()
            .round() as i32;
    }
    let look = TextLook::new(size);
    runs.iter()
        .map(|(family, text, s, _)| {
            area.estimate_text_size(text, &style(family, *s, &look))
                .map_or(0, |(w, _)| w as i32)
        })
        .sum()
}

/// Draw `markup` with the top of its line at `anchor` (pixels of `area`; for upward text the
/// top faces left, so the anchor is the left edge of the line), aligned along the line by
/// `align`.
pub fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    markup: &str,
    anchor: (i32, i32),
    align: Align,
    look: TextLook,
) -> anyhow::Result<()> {
    let total = width(area, markup, look.size);
    let along = match align {
        Align::Start => 0,
        Align::Middle => -total / 2,
        Align::End => -total,
    };
    // Reading frame (along, normal) to pixels: as written, or turned a quarter upwards.
    let at = |along: i32, normal: i32| {
        if look.upwards {
            (anchor.0 + normal, anchor.1 - along)
        } else {
            (anchor.0 + along, anchor.1 + normal)
        }
    };
    let mut pen = along as f32;
    for (family, text, s, top) in layout(markup, look.size) {
        let st = style(family, s, &look);
        let normal = top.round() as i32;
        let start = pen.round() as i32;
        let pieces = if glyphwise() {
            let (glyphs, advance) = glyph_starts(family, &text, s);
            pen += advance;
            glyphs
                .into_iter()
                .map(|(c, x)| (c.to_string(), x))
                .collect()
        } else {
            pen += area.estimate_text_size(&text, &st).map_or(0, |(w, _)| w) as f32;
            vec![(text.clone(), 0)]
        };
        for (piece, offset) in pieces {
            area.draw_text(&piece, &st, at(start + offset, normal))
                .map_err(|e| anyhow::anyhow!("drawing text '{text}': {e:?}"))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spans(markup: &str) -> Vec<(String, Level)> {
        parse(markup)
            .into_iter()
            .map(|s| (s.text, s.level))
            .collect()
    }

    #[test]
    fn markup_gives_sub_and_superscripts() {
        use Level::*;
        assert_eq!(
            spans("K_{PL}"),
            vec![("K".into(), Base), ("PL".into(), Sub)]
        );
        assert_eq!(
            spans("λ_l/λ_s"),
            vec![
                ("λ".into(), Base),
                ("l".into(), Sub),
                ("/λ".into(), Base),
                ("s".into(), Sub)
            ]
        );
        assert_eq!(
            spans("A*/λ_s^2"),
            vec![("A*/λ".into(), Base), ("s".into(), Sub), ("2".into(), Sup)]
        );
        assert_eq!(
            spans("10^{−4} m"),
            vec![("10".into(), Base), ("−4".into(), Sup), (" m".into(), Base)]
        );
        assert_eq!(plain("W/W_0 = 0.01"), "W/W0 = 0.01");
        assert_eq!(flat("W/W_0 = 0.01"), "W/W₀ = 0.01");
        assert_eq!(flat("A*/λ_s^2"), "A*/λₛ²");
        assert_eq!(flat("K_{PL}"), "K_PL");
        assert_eq!(flat("10^{−4}"), "10⁻⁴");
        // A trailing marker is text, and nothing is lost.
        assert_eq!(plain("a_"), "a_");
        assert_eq!(plain(&escape("c128_a^8")), "c128_a^8");
    }

    #[test]
    fn mathematical_letters_go_to_the_math_font() {
        let r = runs("𝒦_PL");
        assert_eq!(r[0], (MATH_FAMILY, "𝒦".to_string()));
        assert_eq!(r[1], (TEXT_FAMILY, "_PL".to_string()));
    }
}

#[cfg(test)]
mod glyph_tests {
    use super::*;

    /// Drawn as one label, each digit's ink starts where ab_glyph's own layout of the whole
    /// string puts it (glyphs positioned at their pen, outlines rasterised in place), within
    /// a pixel: no "12 8" for 128.
    #[test]
    fn each_glyph_of_a_label_starts_where_the_fonts_layout_puts_it() {
        use ab_glyph::{Font, ScaleFont};
        ensure_font().unwrap();
        let (w, h, size) = (900u32, 80u32, 40.0);
        let text = "0123456789";
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let _raster = Glyphwise::on();
            let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw(&area, text, (10, 10), Align::Start, TextLook::new(size)).unwrap();
            area.present().unwrap();
        }
        // Ink columns, grouped into runs separated by blank columns: one run a digit.
        let inked: Vec<bool> = (0..w as usize)
            .map(|x| (0..h as usize).any(|y| buf[(y * w as usize + x) * 3] < 128))
            .collect();
        let starts: Vec<i32> = (0..inked.len())
            .filter(|&x| inked[x] && (x == 0 || !inked[x - 1]))
            .map(|x| x as i32)
            .collect();
        assert_eq!(starts.len(), text.len(), "{starts:?}");
        // The font's own layout.
        let font = font_of(TEXT_FAMILY);
        let scaled = font.as_scaled(size as f32);
        let mut pen = 0f32;
        for (c, &start) in text.chars().zip(&starts) {
            let mut g = scaled.scaled_glyph(c);
            g.position = ab_glyph::point(pen, 0.0);
            let ink = scaled.outline_glyph(g).unwrap().px_bounds().min.x;
            assert!(
                ((10.0 + ink) - start as f32).abs() <= 1.0,
                "{c}: drawn at {start}, the font's layout at {}",
                10.0 + ink
            );
            pen += scaled.h_advance(scaled.glyph_id(c));
        }
    }
}
