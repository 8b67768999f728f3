//! Line plots as PNG (plotters, with a built-in font, so no system font is
//! needed): `cloth3d run --plot` and `cloth3d compare`.

use image::RgbImage;

use crate::scenes::Series;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// One curve: a legend label, points (x, y) and a colour (RGB).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Legend label.
    pub label: String,
    /// The points, in order of x.
    pub points: Vec<(f64, f64)>,
    /// RGB colour.
    pub color: [u8; 3],
}

/// One panel of a figure: a title, a y-axis label and its curves.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title drawn above the panel.
    pub title: String,
    /// Label of the y axis (quantity and unit).
    pub y_label: String,
    /// The curves.
    pub curves: Vec<Curve>,
}

/// Colours of successive curves.
pub const COLORS: [[u8; 3]; 7] = [
    [230, 90, 80],
    [90, 170, 240],
    [120, 200, 110],
    [240, 190, 70],
    [190, 120, 230],
    [80, 210, 200],
    [240, 120, 180],
];

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Draws `panels` stacked top to bottom, sharing the x axis labelled `x_label`,
/// on a `width × height` white picture.
pub fn draw(panels: &[Panel], x_label: &str, width: u32, height: u32) -> Result<RgbImage, String> {
    register_font();
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let areas = root.split_evenly((panels.len().max(1), 1));
        for (panel, area) in panels.iter().zip(areas) {
            draw_panel(panel, x_label, &area)?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    RgbImage::from_raw(width, height, buffer).ok_or_else(|| "picture buffer too small".into())
}

fn draw_panel<DB: DrawingBackend>(
    panel: &Panel,
    x_label: &str,
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), String> {
    let finite = |v: f64| v.is_finite();
    let points = panel.curves.iter().flat_map(|c| c.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in points.filter(|p| finite(p.0) && finite(p.1)) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x1 - x0 <= 0.0 {
        x1 = x0 + 1.0;
    }
    let pad = if y1 > y0 {
        0.05 * (y1 - y0)
    } else {
        0.5 * y0.abs().max(1e-3)
    };
    let (y0, y1) = (y0 - pad, y1 + pad);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 20))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(&panel.y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| e.to_string())?;
    for curve in &panel.curves {
        let [r, g, b] = curve.color;
        let color = RGBColor(r, g, b);
        chart
            .draw_series(LineSeries::new(
                curve
                    .points
                    .iter()
                    .copied()
                    .filter(|p| finite(p.0) && finite(p.1)),
                color.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(curve.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
    }
    if panel.curves.iter().any(|c| !c.label.is_empty()) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(180, 180, 180))
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Three panels of a run over time: energy (J), max stretch (%), max penetration (mm).
pub fn series(series: &Series, title: &str, width: u32, height: u32) -> Result<RgbImage, String> {
    let curve = |values: &[f64], scale: f64, color: [u8; 3], label: &str| Curve {
        label: label.to_string(),
        points: series
            .time
            .iter()
            .zip(values)
            .map(|(&t, &v)| (t, v * scale))
            .collect(),
        color,
    };
    let panels = [
        Panel {
            title: format!("{title}: total energy"),
            y_label: "energy (J)".into(),
            curves: vec![curve(&series.energy, 1.0, COLORS[1], "energy")],
        },
        Panel {
            title: "max stretch".into(),
            y_label: "stretch (%)".into(),
            curves: vec![curve(&series.max_stretch, 100.0, COLORS[0], "max stretch")],
        },
        Panel {
            title: "max penetration".into(),
            y_label: "penetration (mm)".into(),
            curves: vec![curve(
                &series.max_penetration,
                1000.0,
                COLORS[2],
                "max penetration",
            )],
        },
    ];
    draw(&panels, "time (s)", width, height)
}
