//! Plotting helpers shared by every command that draws: one registered font, SVG or PNG chosen
//! by the file extension, and files written whole or not at all.
//!
//! A figure implements [`Figure`] (draw on any plotters backend) and [`render`] writes it;
//! [`LinePlot`] is a ready-made figure of labelled line series for simple charts.

use crate::output::write_atomic;
use plotters::coord::Shift;
use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;
use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Once;
use thiserror::Error;

/// The font every figure uses, shipped with the crate (DejaVu Sans, free license) so that no
/// system font is needed.
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Register the shipped font as plotters' `sans-serif` family, once per process. [`render`]
/// calls it; call it yourself only when drawing on a backend of your own.
pub fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TTF shipped in the repository; a failure here would be a
        // packaging bug, and the drawing would then report FontUnavailable.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Image formats a figure can be written in, chosen by the output file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.svg`: vector, text stays text.
    Svg,
    /// `.png`: bitmap.
    Png,
}

impl ImageFormat {
    /// The format of `path` by its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(ImageFormat::Svg),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(PlotError::Extension {
                path: path.to_owned(),
            }),
        }
    }
}

/// A figure that could not be written.
#[derive(Debug, Error)]
pub enum PlotError {
    /// The output file's extension names no supported format.
    #[error("{path}: unsupported image format (use a .svg or .png file name)")]
    Extension {
        /// The output path.
        path: PathBuf,
    },
    /// plotters failed while drawing (the message is its own).
    #[error("drawing failed: {0}")]
    Draw(String),
    /// Writing or renaming the file failed.
    #[error("{path}: {source}")]
    Io {
        /// The output path.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        PlotError::Draw(e.to_string())
    }
}

/// Draw a chart's series labels the way every figure of the project does: a white, framed box
/// at `position`, sans-serif at `font_size`.
pub fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Result<(), PlotError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", font_size))
        .draw()?;
    Ok(())
}

/// How a legend entry of [`draw_side_legend`] or [`draw_key`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Swatch {
    /// A filled box of this colour (a shaded region).
    Fill(RGBColor),
    /// A line of this colour and width.
    Line(RGBColor, u32),
    /// A dashed line of this colour.
    Dashed(RGBColor),
    /// A dot of this colour.
    Dot(RGBColor),
    /// An open circle of this colour.
    Ring(RGBColor),
    /// An open square of this colour.
    Square(RGBColor),
    /// A cross (x) of this colour.
    Cross(RGBColor),
}

/// Width in pixels of a swatch, before its label.
const SWATCH_WIDTH: i32 = 22;

/// Draw `swatch` with its left end at `x0`, centred on the row `mid`.
fn draw_swatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    swatch: Swatch,
    x0: i32,
    mid: i32,
) -> Result<(), PlotError> {
    let centre = (x0 + SWATCH_WIDTH / 2, mid);
    match swatch {
        Swatch::Fill(c) => {
            let corners = [(x0, mid - 6), (x0 + SWATCH_WIDTH, mid + 6)];
            area.draw(&Rectangle::new(corners, c.filled()))?;
            area.draw(&Rectangle::new(corners, BLACK))?;
        }
        Swatch::Line(c, w) => {
            area.draw(&PathElement::new(
                vec![(x0, mid), (x0 + SWATCH_WIDTH, mid)],
                c.stroke_width(w),
            ))?;
        }
        Swatch::Dashed(c) => {
            for k in 0..3 {
                let a = x0 + 9 * k;
                area.draw(&PathElement::new(
                    vec![(a, mid), (a + 5, mid)],
                    c.stroke_width(2),
                ))?;
            }
        }
        Swatch::Dot(c) => area.draw(&Circle::new(centre, 4, c.filled()))?,
        Swatch::Ring(c) => area.draw(&Circle::new(centre, 4, c.stroke_width(2)))?,
        Swatch::Square(c) => area.draw(&Rectangle::new(
            [(centre.0 - 6, mid - 6), (centre.0 + 6, mid + 6)],
            c.stroke_width(2),
        ))?,
        Swatch::Cross(c) => area.draw(&Cross::new(centre, 4, c.stroke_width(2)))?,
    }
    Ok(())
}

/// A one-row key drawn right-aligned at `right` on row `mid` of `area` (above a chart, where
/// it covers nothing): each entry's swatch, then its label, at `font_size`.
pub fn draw_key<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(Swatch, String)],
    (right, mid): (i32, i32),
    font_size: u32,
) -> Result<(), PlotError> {
    let font = ("sans-serif", font_size).into_font().color(&BLACK);
    let widths = entries
        .iter()
        .map(|(_, label)| {
            let (w, _) = area.estimate_text_size(label, &font)?;
            Ok(SWATCH_WIDTH + 6 + w as i32 + 16)
        })
        .collect::<Result<Vec<i32>, PlotError>>()?;
    let mut x = right - widths.iter().sum::<i32>();
    for ((swatch, label), w) in entries.iter().zip(widths) {
        draw_swatch(area, *swatch, x, mid)?;
        let pos = (x + SWATCH_WIDTH + 6, mid - font_size as i32 / 2 - 1);
        area.draw(&Text::new(label.clone(), pos, font.clone()))?;
        x += w;
    }
    Ok(())
}

/// A legend drawn in its own area beside the charts, so that it never covers data: a title,
/// the entries (swatch and label), then free text lines (the figure's key numbers). Long
/// labels are wrapped at `wrap` characters.
pub fn draw_side_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    entries: &[(Swatch, String)],
    notes: &[String],
    wrap: usize,
) -> Result<(), PlotError> {
    let text = ("sans-serif", 14).into_font().color(&BLACK);
    // Only the regular face is registered (ensure_font): a larger size marks the title.
    let bold = ("sans-serif", 17).into_font().color(&BLACK);
    let (x0, line) = (8, 18);
    let mut y = 12;
    area.draw(&Text::new(title.to_owned(), (x0, y), bold.clone()))?;
    y += line + 6;
    for (swatch, label) in entries {
        draw_swatch(area, *swatch, x0, y + line / 2 - 2)?;
        for (i, piece) in wrap_words(label, wrap).into_iter().enumerate() {
            let indent = if i == 0 { 0 } else { 8 };
            area.draw(&Text::new(piece, (x0 + 30 + indent, y), text.clone()))?;
            y += line;
        }
        y += 4;
    }
    y += 10;
    for note in notes {
        for piece in wrap_words(note, wrap + 4) {
            area.draw(&Text::new(piece, (x0, y), text.clone()))?;
            y += line;
        }
        y += 4;
    }
    Ok(())
}

/// The height in pixels that [`draw_side_legend`] needs for these entries and notes.
pub fn side_legend_height(entries: &[(Swatch, String)], notes: &[String], wrap: usize) -> u32 {
    let mut y = 12 + 18 + 6;
    for (_, label) in entries {
        y += 18 * wrap_words(label, wrap).len() + 4;
    }
    y += 10;
    for note in notes {
        y += 18 * wrap_words(note, wrap + 4).len() + 4;
    }
    (y + 12) as u32
}

/// Split `s` into lines of at most `width` characters at spaces (a longer word stays whole).
/// `value +- error` is never split, nor a signed number from the word before it (`BIC +9.0`),
/// nor `%` from its number: an error or a difference read on the next line reads as a value
/// of its own.
pub fn wrap_words(s: &str, width: usize) -> Vec<String> {
    // Words, with `+-` joined to the words on either side and a signed number to the one
    // before.
    let signed = |w: &str| {
        let mut c = w.chars();
        matches!(c.next(), Some('+' | '-')) && c.next().is_some_and(|d| d.is_ascii_digit())
    };
    let mut words: Vec<String> = Vec::new();
    let mut glue = false;
    for word in s.split_whitespace() {
        match words.last_mut() {
            Some(last) if glue || word == "+-" || signed(word) || word.starts_with('%') => {
                last.push(' ');
                last.push_str(word);
            }
            _ => words.push(word.to_owned()),
        }
        glue = word == "+-";
    }
    let mut out = Vec::new();
    let mut line = String::new();
    for word in words {
        if !line.is_empty() && line.len() + 1 + word.len() > width {
            out.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(&word);
    }
    if !line.is_empty() {
        out.push(line);
    }
    out
}

/// Which points of a line to draw so that the drawn path stays the same to the pixel: of each
/// run of points in one pixel column (`pixels`, backend coordinates in drawing order), the
/// first, the lowest, the highest and the last, and no point twice in a row on one pixel. A
/// line of a million frames is then a few points per column. Indices ascending.
pub fn thin_line(pixels: &[(i32, i32)]) -> Vec<usize> {
    let mut keep = Vec::new();
    let mut start = 0;
    while start < pixels.len() {
        let x = pixels[start].0;
        let end = start + pixels[start..].iter().take_while(|p| p.0 == x).count();
        let column = start..end;
        let low = column.clone().min_by_key(|&i| pixels[i].1).unwrap_or(start);
        let high = column.max_by_key(|&i| pixels[i].1).unwrap_or(start);
        let mut four = [start, low, high, end - 1];
        four.sort_unstable();
        for i in four {
            if keep.last().is_none_or(|&j: &usize| pixels[j] != pixels[i]) {
                keep.push(i);
            }
        }
        start = end;
    }
    keep
}

/// Which of a series' points to draw, at most `budget` (plus the first and last), so that what
/// the eye looks for stays: the points at `pixels` (backend coordinates), each with a `key`
/// (its distance from the model). A point on a pixel already drawn is left out; beyond the
/// budget, every `group` pixel columns keep their points of the largest and the smallest key
/// (the outliers and the extremes never go), and an even sample of the rest fills the budget.
/// Groups much wider than a dot keep the extremes without drawing the noise's envelope as a
/// ridge of dots. Indices ascending.
pub fn thin_points(pixels: &[(i32, i32)], keys: &[f64], budget: usize, group: i32) -> Vec<usize> {
    let mut seen = std::collections::HashSet::new();
    let unique: Vec<usize> = (0..pixels.len())
        .filter(|&i| seen.insert(pixels[i]))
        .collect();
    let (Some(&first), Some(&last)) = (unique.first(), unique.last()) else {
        return unique;
    };
    if unique.len() <= budget {
        return unique;
    }
    let x0 = unique.iter().map(|&i| pixels[i].0).min().unwrap_or(0);
    let x1 = unique.iter().map(|&i| pixels[i].0).max().unwrap_or(0);
    let group = group.max(1);
    let groups = ((x1 - x0) / group) as usize + 1;
    let mut low: Vec<Option<usize>> = vec![None; groups];
    let mut high: Vec<Option<usize>> = vec![None; groups];
    for &i in &unique {
        let g = ((pixels[i].0 - x0) / group) as usize;
        if low[g].is_none_or(|j| keys[i].total_cmp(&keys[j]).is_lt()) {
            low[g] = Some(i);
        }
        if high[g].is_none_or(|j| keys[i].total_cmp(&keys[j]).is_gt()) {
            high[g] = Some(i);
        }
    }
    let mut kept = vec![false; pixels.len()];
    for i in low.into_iter().chain(high).flatten().chain([first, last]) {
        kept[i] = true;
    }
    let marked = kept.iter().filter(|k| **k).count();
    let rest: Vec<usize> = unique.iter().copied().filter(|&i| !kept[i]).collect();
    let room = budget.saturating_sub(marked).min(rest.len());
    for k in 0..room {
        kept[rest[k * rest.len() / room]] = true;
    }
    (0..pixels.len()).filter(|&i| kept[i]).collect()
}

/// Something that draws itself on a plotters drawing area of any backend.
pub trait Figure {
    /// Size in pixels (width, height).
    fn size(&self) -> (u32, u32) {
        (1000, 700)
    }

    /// Draw on `root` (already sized; filled white by [`render`]).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError>;
}

/// Write `figure` to `path` as SVG or PNG (by extension). Nothing is left at `path` unless the
/// whole image was written: either is drawn into memory and written through a temporary
/// sibling and a rename.
pub fn render(path: &Path, figure: &impl Figure) -> Result<(), PlotError> {
    ensure_font();
    let io = |source| PlotError::Io {
        path: path.to_owned(),
        source,
    };
    match ImageFormat::from_path(path)? {
        ImageFormat::Svg => {
            let svg = svg_string(figure)?;
            write_atomic(path, |w| w.write_all(svg.as_bytes())).map_err(io)
        }
        ImageFormat::Png => {
            // Drawn into memory and encoded with the png crate (not plotters' image-crate
            // encoder, which costs a minute and a half of a cold build for the JPEG, GIF and BMP
            // codecs no figure uses), then written atomically like the SVG.
            let (width, height) = figure.size();
            let mut rgb = vec![0u8; width as usize * height as usize * 3];
            {
                let root =
                    BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
                root.fill(&WHITE)?;
                figure.draw(&root)?;
                root.present()?;
            }
            write_atomic(path, |w| encode_png(w, width, height, &rgb)).map_err(io)
        }
    }
}

/// `figure` drawn as an SVG document in memory (a notebook shows it inline).
pub fn svg_string(figure: &impl Figure) -> Result<String, PlotError> {
    ensure_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, figure.size()).into_drawing_area();
        root.fill(&WHITE)?;
        figure.draw(&root)?;
        root.present()?;
    }
    Ok(svg)
}

/// Encode 8-bit RGB pixels, row by row from the top, as a PNG.
fn encode_png(out: &mut dyn Write, width: u32, height: u32, rgb: &[u8]) -> std::io::Result<()> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

/// One line series of a [`LinePlot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (empty: no legend entry).
    pub label: String,
    /// Points (x, y) drawn in order; a NaN coordinate breaks the line.
    pub points: Vec<(f64, f64)>,
    /// Line colour.
    pub color: RGBColor,
    /// Line width in pixels.
    pub width: u32,
}

/// A chart of labelled line series: the simple figure fit, plan and bench reports need.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Title above the chart.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// x range; `None`: the data's range.
    pub x_range: Option<Range<f64>>,
    /// y range; `None`: the data's range with a 5 % margin.
    pub y_range: Option<Range<f64>>,
    /// The series, drawn in order.
    pub series: Vec<Series>,
}

/// The finite range of `values` widened by `margin` of its span (a unit range when empty or
/// flat).
pub fn data_range(values: impl IntoIterator<Item = f64>, margin: f64) -> Range<f64> {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return 0.0..1.0;
    }
    let span = if hi > lo { hi - lo } else { 1.0 };
    (lo - margin * span)..(hi + margin * span)
}

/// Split points into runs of finite points (a NaN or infinite coordinate ends a run).
pub fn finite_runs(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut run = Vec::new();
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() {
            run.push((x, y));
        } else if !run.is_empty() {
            out.push(std::mem::take(&mut run));
        }
    }
    if !run.is_empty() {
        out.push(run);
    }
    out
}

impl Figure for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let x_range = self
            .x_range
            .clone()
            .unwrap_or_else(|| data_range(all().map(|p| p.0), 0.0));
        let y_range = self
            .y_range
            .clone()
            .unwrap_or_else(|| data_range(all().map(|p| p.1), 0.05));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(x_range, y_range)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(("sans-serif", 14))
            .draw()?;
        let mut labelled = false;
        for s in &self.series {
            let style = s.color.stroke_width(s.width);
            for (i, run) in finite_runs(&s.points).into_iter().enumerate() {
                let drawn = chart.draw_series(LineSeries::new(run, style))?;
                if i == 0 && !s.label.is_empty() {
                    labelled = true;
                    let color = s.color;
                    drawn.label(&s.label).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                }
            }
        }
        if labelled {
            draw_legend(&mut chart, SeriesLabelPosition::MiddleRight, 14)?;
        }
        Ok(())
    }
}

/// Draw line series to an SVG or PNG file (by extension): [`render`] of a [`LinePlot`].
pub fn draw_lines(path: &Path, plot: &LinePlot) -> Result<(), PlotError> {
    render(path, plot)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_is_refused_and_nothing_written() {
        // Removed with everything in it at the end of the test.
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let path = dir.join("figure.jpg");
        let plot = LinePlot {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            x_range: None,
            y_range: None,
            series: Vec::new(),
        };
        assert!(matches!(
            draw_lines(&path, &plot),
            Err(PlotError::Extension { .. })
        ));
        assert!(!path.exists());
    }

    /// A thinned line covers the same pixels column by column: each column's lowest and
    /// highest pixel, where it enters and where it leaves, from far fewer points.
    #[test]
    fn thin_line_keeps_every_columns_extent() {
        // A noisy sine over 100 columns, 300 points a column.
        let pixels: Vec<(i32, i32)> = (0..30_000)
            .map(|i| {
                let t = i as f64 / 300.0;
                let wobble = ((i * 7919) % 13) as f64 - 6.0;
                (t as i32, (200.0 + 80.0 * (t / 9.0).sin() + wobble) as i32)
            })
            .collect();
        let kept = thin_line(&pixels);
        assert!(kept.len() <= 4 * 100, "{}", kept.len());
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        assert_eq!((kept[0], *kept.last().unwrap()), (0, pixels.len() - 1));
        for x in 0..100 {
            let column = |idx: &mut dyn Iterator<Item = usize>| {
                let ys: Vec<i32> = idx
                    .filter(|&i| pixels[i].0 == x)
                    .map(|i| pixels[i].1)
                    .collect();
                (
                    ys.iter().min().copied(),
                    ys.iter().max().copied(),
                    ys.first().copied(),
                    ys.last().copied(),
                )
            };
            assert_eq!(
                column(&mut kept.iter().copied()),
                column(&mut (0..pixels.len())),
                "column {x}"
            );
        }
    }

    /// Thinned points stay within the budget, keep the first and the last, and keep every
    /// group's largest and smallest key: a lone outlier is never thinned away.
    #[test]
    fn thin_points_keeps_the_extremes_within_the_budget() {
        let n = 50_000;
        let keys: Vec<f64> = (0..n)
            .map(|i| match i {
                31_337 => 40.0,
                4_242 => -25.0,
                _ => (((i * 7919) % 101) as f64 - 50.0) / 20.0,
            })
            .collect();
        let pixels: Vec<(i32, i32)> = (0..n)
            .map(|i| ((i / 60) as i32, (300.0 - 10.0 * keys[i]) as i32))
            .collect();
        let kept = thin_points(&pixels, &keys, 1000, 10);
        assert!(kept.len() <= 1000 + 2, "{}", kept.len());
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        for must in [0, n - 1, 31_337, 4_242] {
            assert!(kept.contains(&must), "{must}");
        }
        // Every group of ten columns keeps its highest and lowest pixel.
        let groups = pixels.last().unwrap().0 / 10 + 1;
        for g in 0..groups {
            let extent = |idx: &mut dyn Iterator<Item = usize>| {
                let ys: Vec<i32> = idx
                    .filter(|&i| pixels[i].0 / 10 == g)
                    .map(|i| pixels[i].1)
                    .collect();
                (ys.iter().min().copied(), ys.iter().max().copied())
            };
            assert_eq!(
                extent(&mut kept.iter().copied()),
                extent(&mut (0..n)),
                "group {g}"
            );
        }
        // Within the budget everything distinct is drawn, a pixel once.
        let few = [(1, 1), (2, 2), (1, 1), (3, 3)];
        assert_eq!(thin_points(&few, &[0.0; 4], 10, 10), vec![0, 1, 3]);
    }

    /// A wrapped line never ends or starts at `+-`: a value and its error stay together.
    #[test]
    fn wrap_keeps_a_value_with_its_error() {
        let lines = wrap_words("mu_kinetic_positive = 0.23999 +- 1.9e-5 (95 %)", 34);
        assert_eq!(
            lines,
            vec!["mu_kinetic_positive =", "0.23999 +- 1.9e-5 (95 %)"],
            "{lines:?}"
        );
        assert_eq!(wrap_words("a b c", 3), vec!["a b", "c"]);
        assert_eq!(
            wrap_words("static: mu 0.25311, BIC +11477372.4 against", 24),
            vec!["static: mu 0.25311,", "BIC +11477372.4 against"]
        );
    }

    #[test]
    fn line_plot_writes_svg_and_png_with_text() {
        // Removed with everything in it at the end of the test.
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let plot = LinePlot {
            title: "sine".into(),
            x_label: "t [s]".into(),
            y_label: "y".into(),
            x_range: None,
            y_range: None,
            series: vec![Series {
                label: "sin t".into(),
                points: (0..50)
                    .map(|i| (i as f64 * 0.1, (i as f64 * 0.1).sin()))
                    .collect(),
                color: BLUE,
                width: 2,
            }],
        };
        for name in ["a.svg", "a.png"] {
            let path = dir.join(name);
            draw_lines(&path, &plot).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            assert!(bytes.len() > 1000, "{name}: {} bytes", bytes.len());
        }
        let svg = std::fs::read_to_string(dir.join("a.svg")).unwrap();
        assert!(svg.contains("sin t") && svg.trim_end().ends_with("</svg>"));
    }
}
