//! PNG plots with plotters, using a font bundled in the repository (`assets/fonts/DejaVuSans.ttf`)
//! so that plots render on a fresh machine with no system font library.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::{Error, Result};

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the bundled font under the family name "sans-serif" (once per process).
pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled into the binary; a parse failure would be a build defect that
        // every plot test catches, so it is reported there rather than here.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One named series of (x, y) points, drawn as a line with markers.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A series from a label and points.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self { label: label.into(), points }
    }
}

/// An x–y line plot (error against time, convergence curves …).
#[derive(Clone, Debug)]
pub struct LinePlot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label (with units).
    pub x_label: String,
    /// y-axis label (with units).
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
}

impl LinePlot {
    /// A plot with linear axes and no series.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: false,
            log_y: false,
            series: Vec::new(),
        }
    }

    /// Sets both axes' scales.
    pub fn log(mut self, log_x: bool, log_y: bool) -> Self {
        self.log_x = log_x;
        self.log_y = log_y;
        self
    }

    /// Adds a series.
    pub fn with(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Draws the plot into a 900×600 PNG. Points that cannot be shown (non-finite, or ≤ 0 on a
    /// log axis) are left out; a plot with no drawable point still renders (empty axes).
    pub fn write_png(&self, path: &Path) -> Result<PathBuf> {
        register_font();
        if let Some(dir) = path.parent() {
            crate::out::ensure_dir(dir)?;
        }
        let plot_err = |e: &dyn std::fmt::Display| Error::Plot { path: path.to_path_buf(), msg: e.to_string() };
        let keep =
            |x: f64, y: f64| x.is_finite() && y.is_finite() && (!self.log_x || x > 0.0) && (!self.log_y || y > 0.0);
        let pts: Vec<(f64, f64)> =
            self.series.iter().flat_map(|s| s.points.iter().copied()).filter(|&(x, y)| keep(x, y)).collect();
        let range = |vals: Vec<f64>, log: bool| -> (f64, f64) {
            let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if !lo.is_finite() {
                return if log { (0.1, 10.0) } else { (0.0, 1.0) };
            }
            if log {
                let (a, b) = if hi / lo < 1.0001 { (lo / 2.0, hi * 2.0) } else { (lo, hi) };
                (a / 1.3, b * 1.3)
            } else {
                let pad = if hi - lo > 0.0 { 0.05 * (hi - lo) } else { 0.5 * lo.abs().max(1.0) };
                (lo - pad, hi + pad)
            }
        };
        let (x0, x1) = range(pts.iter().map(|p| p.0).collect(), self.log_x);
        let (y0, y1) = range(pts.iter().map(|p| p.1).collect(), self.log_y);

        let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(&e))?;
        let mut builder = ChartBuilder::on(&root);
        builder.caption(&self.title, ("sans-serif", 22)).margin(15).x_label_area_size(45).y_label_area_size(80);
        // plotters types the chart by its coordinate kinds, so the four axis combinations are four
        // instantiations of one generic drawing routine.
        macro_rules! draw {
            ($xr:expr, $yr:expr) => {{
                let mut chart = builder.build_cartesian_2d($xr, $yr).map_err(|e| plot_err(&e))?;
                chart
                    .configure_mesh()
                    .x_desc(&self.x_label)
                    .y_desc(&self.y_label)
                    .label_style(("sans-serif", 14))
                    .x_label_formatter(&|v: &f64| tick_label(*v))
                    .y_label_formatter(&|v: &f64| tick_label(*v))
                    .draw()
                    .map_err(|e| plot_err(&e))?;
                for (i, s) in self.series.iter().enumerate() {
                    let color = Palette99::pick(i).to_rgba();
                    let data: Vec<(f64, f64)> = s.points.iter().copied().filter(|&(x, y)| keep(x, y)).collect();
                    chart
                        .draw_series(LineSeries::new(data.clone(), color.stroke_width(2)))
                        .map_err(|e| plot_err(&e))?
                        .label(s.label.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                    chart
                        .draw_series(data.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                        .map_err(|e| plot_err(&e))?;
                }
                if self.series.len() > 1 || self.series.iter().any(|s| !s.label.is_empty()) {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 14))
                        .draw()
                        .map_err(|e| plot_err(&e))?;
                }
            }};
        }
        match (self.log_x, self.log_y) {
            (false, false) => draw!(x0..x1, y0..y1),
            (true, false) => draw!((x0..x1).log_scale(), y0..y1),
            (false, true) => draw!(x0..x1, (y0..y1).log_scale()),
            (true, true) => draw!((x0..x1).log_scale(), (y0..y1).log_scale()),
        }
        root.present().map_err(|e| plot_err(&e))?;
        Ok(path.to_path_buf())
    }
}

/// An axis tick as a short label: three significant digits, trailing zeros dropped, scientific
/// notation outside [1e-3, 1e5). Log axes put ticks at values such as `9.999999999999999e-5` (the
/// float nearest 10⁻⁴ reached by repeated division); printed raw they overflow the label area.
pub fn tick_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        let (mant, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mant = if mant.contains('.') { mant.trim_end_matches('0').trim_end_matches('.') } else { mant };
        return format!("{mant}e{exp}");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(9.999999999999999e-5), "1e-4");
        assert_eq!(tick_label(1e-9), "1e-9");
        assert_eq!(tick_label(2.5e-7), "2.5e-7");
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(0.125), "0.125");
        assert_eq!(tick_label(0.001), "0.001");
        assert_eq!(tick_label(250.0), "250");
        assert_eq!(tick_label(-12.5), "-12.5");
        assert_eq!(tick_label(123456.0), "1.23e5");
        assert_eq!(tick_label(0.0), "0");
    }

    #[test]
    fn renders_log_log_png_with_bundled_font() {
        let path = std::env::temp_dir().join(format!("xtask-plot-{}.png", std::process::id()));
        LinePlot::new("error vs time", "time (s)", "relative error")
            .log(true, true)
            .with(Series::new("a", vec![(1e-3, 1e-2), (1e-2, 1e-6), (0.1, 0.0), (f64::NAN, 1.0)]))
            .with(Series::new("b", vec![(2e-3, 1e-3)]))
            .write_png(&path)
            .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn empty_plot_still_renders() {
        let path = std::env::temp_dir().join(format!("xtask-plot-empty-{}.png", std::process::id()));
        LinePlot::new("empty", "x", "y").write_png(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
    }
}
