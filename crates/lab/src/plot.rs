//! Line charts as SVG (plotters), for the experiments' figures.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use std::path::Path;

/// One curve.
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points `(x, y)`; NaN `y` values are left out.
    pub points: Vec<(f64, f64)>,
}

/// A line chart with optional horizontal reference lines.
pub struct LineChart<'a> {
    /// Caption.
    pub title: String,
    /// X axis label.
    pub x_label: &'a str,
    /// Y axis label.
    pub y_label: &'a str,
    /// The curves.
    pub series: Vec<Series>,
    /// Dashed horizontal lines `(legend, y)`.
    pub reference: Vec<(String, f64)>,
}

/// Render `chart` to an SVG file at `path` (written atomically).
pub fn write_svg(chart: &LineChart, path: &Path) -> Result<()> {
    let mut svg = String::new();
    draw(chart, &mut svg).map_err(|e| anyhow!("plotting {}: {e}", chart.title))?;
    raykit_io::write_atomic(path, |w| w.write_all(svg.as_bytes()))
        .map_err(|e| anyhow!("{}: {e}", path.display()))
}

fn draw(chart: &LineChart, svg: &mut String) -> Result<(), Box<dyn std::error::Error>> {
    let finite = |v: &f64| v.is_finite();
    let xs = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .chain(chart.reference.iter().map(|r| r.1))
        .filter(finite);
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let y1 = ys.fold(0f64, f64::max);
    let (x0, x1) = if x0 < x1 {
        (x0, x1)
    } else {
        (x0 - 1.0, x0 + 1.0)
    };
    let y1 = if y1 > 0.0 { y1 * 1.1 } else { 1.0 };
    let root = SVGBackend::with_string(svg, (720, 450)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut c = ChartBuilder::on(&root)
        .caption(chart.title.as_str(), ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, 0f64..y1)?;
    c.configure_mesh()
        .x_desc(chart.x_label)
        .y_desc(chart.y_label)
        .draw()?;
    for (i, s) in chart.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.1.is_finite())
            .collect();
        c.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(s.name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        c.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    for (i, (name, y)) in chart.reference.iter().enumerate() {
        let color = Palette99::pick(chart.series.len() + i).to_rgba();
        let y = *y;
        let xs: Vec<f64> = (0..40).map(|k| x0 + (x1 - x0) * k as f64 / 39.0).collect();
        let dashes: Vec<PathElement<(f64, f64)>> = xs
            .chunks(2)
            .map(|w| PathElement::new(vec![(w[0], y), (w[w.len() - 1], y)], color.stroke_width(2)))
            .collect();
        c.draw_series(dashes)?
            .label(name.as_str())
            .legend(move |(x, yy)| {
                PathElement::new(vec![(x, yy), (x + 20, yy)], color.stroke_width(2))
            });
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
