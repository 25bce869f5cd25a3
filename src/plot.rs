//! Plots of a run, written next to its data as PNG and SVG (issue 4): the total contact
//! force against time (with the analytic plateau `E S |v0| / c0` over `2L/c0` when the
//! summary has the impacting-bar reference), the kinetic, potential and total energies,
//! and the largest penetration per step. [`plot_run`] reads only `history.csv` and
//! `summary.json`, so `signorini plot DIR` redraws any finished (or killed) run.
//!
//! Drawing is plotters'; text uses DejaVu Sans embedded by the `dejavu` crate and
//! rasterized by `ab_glyph`, so no system font library (fontconfig, freetype) is needed.
//! Series longer than 4000 samples are reduced to the minimum and maximum of each of
//! 2000 buckets, which keeps every peak visible.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Error;

/// One curve: legend, points, colour, dashed.
struct Series {
    name: String,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

/// One figure: file stem, title, axis labels, curves.
struct Figure {
    stem: &'static str,
    title: String,
    x: &'static str,
    y: &'static str,
    series: Vec<Series>,
    legend: SeriesLabelPosition,
}

/// Tick labels: plain decimals in [1e-3, 1e5), otherwise scientific with 3 digits.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.2e}")
    }
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(plain_reason(&e.to_string())),
    }
}

/// The operating system's reason inside a drawing backend's error, which plotters
/// prints as Rust debug text (`Drawing backend error: ImageError(IoError(Os { code:
/// 21, kind: IsADirectory, message: "Is a directory" }))`): its `message` when there is
/// one, else the text after the backend's prefixes.
fn plain_reason(text: &str) -> String {
    if let Some(rest) = text.split("message: \"").nth(1)
        && let Some(m) = rest.split('"').next()
    {
        return m.to_string();
    }
    let mut t = text;
    for prefix in ["backend error: ", "Drawing backend error: "] {
        t = t.trim_start_matches(prefix);
    }
    t.to_string()
}

/// Opens `path` for writing before anything is drawn into it, so that a plot that
/// cannot be written is reported with the operating system's own reason and the path
/// (not the drawing backend's debug text).
fn writable(path: &Path) -> Result<(), Error> {
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(path)
        .map(drop)
        .map_err(|e| Error::Write {
            path: path.to_path_buf(),
            source: e,
        })
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid TrueType font; registration cannot fail on it
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Min/max decimation to at most `2 × buckets` points.
fn decimate(p: Vec<(f64, f64)>, buckets: usize) -> Vec<(f64, f64)> {
    if p.len() <= 2 * buckets {
        return p;
    }
    let size = p.len().div_ceil(buckets);
    let mut out = Vec::with_capacity(2 * buckets);
    for chunk in p.chunks(size) {
        let lo = chunk.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let hi = chunk.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        if lo.0 <= hi.0 {
            out.extend([*lo, *hi]);
        } else {
            out.extend([*hi, *lo]);
        }
    }
    out
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, f: &Figure) -> Result<(), String> {
    draw_labeled(root, f, f.x, f.y)
}

fn draw_labeled<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    f: &Figure,
    xl: &str,
    yl: &str,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let all = f.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in all.filter(|(x, y)| x.is_finite() && y.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    // a history spanning ±1e308 has an infinite span: plotters' tick search then never
    // ends; hold the axes to half the float range
    let lim = f64::MAX / 4.0;
    (x0, x1, y0, y1) = (x0.max(-lim), x1.min(lim), y0.max(-lim), y1.min(lim));
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    let pad = 0.05 * (y1 - y0).max(y1.abs().max(y0.abs()) * 1e-3).max(1e-300);
    let (y0, y1) = (y0 - pad, y1 + pad);
    let mut chart = ChartBuilder::on(&root)
        .caption(&f.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(xl)
        .y_desc(yl)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    for s in &f.series {
        let color = s.color;
        let style = color.stroke_width(2);
        let anno = if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(s.points.iter().copied(), 8, 6, style))
                .map_err(e)?
        } else {
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), style))
                .map_err(e)?
        };
        anno.label(s.name.as_str()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2))
        });
    }
    chart
        .configure_series_labels()
        .position(f.legend.clone())
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// The complete lines of a history, as the history reader takes them
/// ([`crate::io::complete_lines`]).
pub use crate::io::complete_lines;

/// Reads `dir/history.csv` (or its `.part` when the run was killed) and
/// `dir/summary.json` (optional) and writes `contact_force`, `energy` and `violation`
/// as `.png` and `.svg` into `dir`. Returns the files written.
pub fn plot_run(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    register_font();
    let mut hist = dir.join("history.csv");
    if !hist.exists() && dir.join("history.csv.part").exists() {
        hist = dir.join("history.csv.part");
    }
    let table = crate::io::read_history(&hist)?;
    if table.header.is_empty() {
        return Err(plot_error(&hist, "empty file"));
    }
    let col = |name: &str| table.column(name);
    let need =
        |name: &str| col(name).ok_or_else(|| plot_error(&hist, format!("no `{name}` column")));
    let (t, ke, pe, viol) = (
        need("time")?,
        need("kinetic_energy")?,
        need("potential_energy")?,
        need("max_violation")?,
    );
    let header = &table.header;
    let impulses: Vec<usize> = (0..header.len())
        .filter(|&i| header[i].starts_with("impulse_") || header[i] == "total_impulse")
        .collect();
    let rows = &table.rows;
    let summary: Option<serde_json::Value> = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok());
    let dt = summary
        .as_ref()
        .and_then(|s| s["dt"].as_f64())
        .or_else(|| {
            // the history's own step: time / step of the first row
            rows.first().map(|r| r[t] / r[0].max(1.0))
        })
        .unwrap_or(1.0);
    let series = |f: &dyn Fn(&[f64]) -> f64| -> Vec<(f64, f64)> {
        decimate(rows.iter().map(|r| (r[t], f(r))).collect(), 2000)
    };
    let mut force = vec![Series {
        name: "Σ P / h".into(),
        points: series(&|r| impulses.iter().map(|&i| r[i]).sum::<f64>() / dt),
        color: RGBColor(31, 119, 180),
        dashed: false,
    }];
    if let Some(c) = summary
        .as_ref()
        .map(|s| &s["contact"])
        .filter(|c| c.is_object())
    {
        let f = c["analytic_force"].as_f64().unwrap_or(f64::NAN);
        let t0 = c["first_contact_time"].as_f64().unwrap_or(0.0);
        let d = c["analytic_duration"].as_f64().unwrap_or(0.0);
        force.push(Series {
            name: format!("analytic E S |v0|/c0 = {f:.3} N"),
            points: vec![(t0, f), (t0 + d, f)],
            color: RGBColor(214, 39, 40),
            dashed: true,
        });
    }
    let scheme = summary
        .as_ref()
        .and_then(|s| s["scheme"].as_str().map(str::to_string))
        .unwrap_or_default();
    let figures = [
        Figure {
            stem: "contact_force",
            title: format!("Contact force ({scheme})"),
            x: "time (s)",
            y: "force (N)",
            series: force,
            legend: SeriesLabelPosition::UpperRight,
        },
        Figure {
            stem: "energy",
            title: format!("Energy ({scheme})"),
            x: "time (s)",
            y: "energy (J)",
            series: vec![
                Series {
                    name: "kinetic".into(),
                    points: series(&|r| r[ke]),
                    color: RGBColor(31, 119, 180),
                    dashed: false,
                },
                Series {
                    name: "potential (elastic + gravity)".into(),
                    points: series(&|r| r[pe]),
                    color: RGBColor(44, 160, 44),
                    dashed: false,
                },
                Series {
                    name: "total".into(),
                    points: series(&|r| r[ke] + r[pe]),
                    color: BLACK,
                    dashed: false,
                },
            ],
            legend: SeriesLabelPosition::MiddleRight,
        },
        Figure {
            stem: "violation",
            title: format!("Largest penetration per step ({scheme})"),
            x: "time (s)",
            y: "penetration (m)",
            series: vec![Series {
                name: "max(−g, 0)".into(),
                points: series(&|r| r[viol]),
                color: RGBColor(148, 103, 189),
                dashed: false,
            }],
            legend: SeriesLabelPosition::UpperRight,
        },
    ];
    let mut written = Vec::new();
    for f in &figures {
        let png = dir.join(format!("{}.png", f.stem));
        writable(&png)?;
        draw(BitMapBackend::new(&png, (1000, 600)).into_drawing_area(), f)
            .map_err(|e| plot_error(&png, e))?;
        let svg = dir.join(format!("{}.svg", f.stem));
        writable(&svg)?;
        draw(SVGBackend::new(&svg, (1000, 600)).into_drawing_area(), f)
            .map_err(|e| plot_error(&svg, e))?;
        written.extend([png, svg]);
    }
    Ok(written)
}

/// One curve of [`lines`]: legend and points.
pub struct Curve {
    /// Legend.
    pub name: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
}

const PALETTE: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(0, 0, 0),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(174, 199, 232),
];

/// Draws `curves` as lines (with markers on log–log axes when `log`) into
/// `stem.png` and `stem.svg`; returns the two paths. Used by the studies.
pub fn lines(
    stem: &Path,
    title: &str,
    x: &'static str,
    y: &'static str,
    curves: &[Curve],
    log: bool,
) -> Result<Vec<PathBuf>, Error> {
    register_font();
    let mut out = Vec::new();
    for ext in ["png", "svg"] {
        let path = stem.with_extension(ext);
        writable(&path)?;
        let r = if ext == "png" {
            draw_lines(
                BitMapBackend::new(&path, (1000, 600)).into_drawing_area(),
                title,
                x,
                y,
                curves,
                log,
            )
        } else {
            draw_lines(
                SVGBackend::new(&path, (1000, 600)).into_drawing_area(),
                title,
                x,
                y,
                curves,
                log,
            )
        };
        r.map_err(|e| plot_error(&path, e))?;
        out.push(path);
    }
    Ok(out)
}

fn draw_lines<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    xl: &str,
    yl: &str,
    curves: &[Curve],
    log: bool,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let ok = |x: f64, y: f64| x.is_finite() && y.is_finite() && (!log || (x > 0.0 && y > 0.0));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in curves.iter().flat_map(|c| c.points.iter()) {
        if ok(x, y) {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
    }
    if log {
        let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 2.0, y1 * 2.0);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(xl)
            .y_desc(yl)
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(e)?;
        for (i, c) in curves.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let pts: Vec<(f64, f64)> = c
                .points
                .iter()
                .copied()
                .filter(|&(x, y)| ok(x, y))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map_err(e)?
                .label(c.name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(e)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
        return root.present().map_err(e);
    }
    let f = Figure {
        stem: "",
        title: title.to_string(),
        x: "",
        y: "",
        series: curves
            .iter()
            .enumerate()
            .map(|(i, c)| Series {
                name: c.name.clone(),
                points: c.points.clone(),
                color: PALETTE[i % PALETTE.len()],
                dashed: false,
            })
            .collect(),
        legend: SeriesLabelPosition::UpperRight,
    };
    draw_labeled(root, &f, xl, yl)
}
