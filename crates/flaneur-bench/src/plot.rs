//! PNG line plots of the experiments (plotters, bitmap backend). The font is compiled
//! in, so a plot looks the same on every machine whatever fonts it has installed.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use flaneur::error::{Error, Result};

static FONT: &[u8] = include_bytes!("../../../data/fonts/DejaVuSans.ttf");

/// One line of a plot.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A plot: title, axis labels and its lines.
#[derive(Clone, Debug)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(200, 40, 40),
    RGBColor(30, 100, 200),
    RGBColor(40, 150, 60),
    RGBColor(150, 80, 180),
    RGBColor(230, 140, 20),
    RGBColor(60, 60, 60),
];

/// Series with more points than this are drawn one pixel wide.
const DENSE_POINTS: usize = 200;

fn register_font() -> std::result::Result<(), String> {
    static DONE: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| "the plot font does not load".to_string())
    })
    .clone()
}

/// Draws `plot` into a PNG at `path` (800 × 500).
pub fn line_plot(path: &Path, plot: &LinePlot) -> Result<()> {
    draw(path, plot).map_err(|what| Error::BadInput {
        path: path.to_path_buf(),
        what: format!("cannot draw the plot: {what}"),
    })
}

fn draw(path: &Path, plot: &LinePlot) -> std::result::Result<(), String> {
    register_font()?;
    let points = || plot.series.iter().flat_map(|s| s.points.iter().copied());
    if points().any(|(x, y)| !x.is_finite() || !y.is_finite()) {
        return Err("a point is not finite".into());
    }
    let (x0, x1) = points().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (x, _)| {
        (a.min(x), b.max(x))
    });
    let y1 = points().fold(0.0f64, |b, (_, y)| b.max(y));
    let (x0, x1) = if x0 < x1 { (x0, x1) } else { (0.0, 1.0) };
    let y1 = if y1 > 0.0 { y1 * 1.05 } else { 1.0 };
    let (width, height) = (800u32, 500u32);
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    draw_into(&mut pixels, (width, height), plot, (x0, x1), y1)?;
    image::save_buffer(path, &pixels, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())
}

fn draw_into(
    pixels: &mut [u8],
    size: (u32, u32),
    plot: &LinePlot,
    (x0, x1): (f64, f64),
    y1: f64,
) -> std::result::Result<(), String> {
    let root = BitMapBackend::with_buffer(pixels, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, 0.0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, s) in plot.series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        // A polyline wider than a pixel joins its segments with miters, which shoot far
        // past the sharp corners of a dense series (a frame-time trace): draw those thin.
        let width = if s.points.len() > DENSE_POINTS { 1 } else { 2 };
        chart
            .draw_series(LineSeries::new(
                s.points.iter().copied(),
                color.stroke_width(width),
            ))
            .map_err(|e| e.to_string())?
            .label(&s.name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png_and_refuses_nan() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let mut plot = LinePlot {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![Series {
                name: "a".into(),
                points: vec![(0.0, 1.0), (1.0, 3.0)],
            }],
        };
        line_plot(&path, &plot).unwrap();
        assert_eq!(&std::fs::read(&path).unwrap()[1..4], b"PNG");
        plot.series[0].points.push((2.0, f64::NAN));
        assert!(line_plot(&dir.path().join("q.png"), &plot).is_err());
    }
}
