//! Log–log line charts as SVG text, for the benchmarks' plots (`bench-scale --plot`):
//! panels side by side, decade ticks, one coloured line with markers per series.

use std::fmt::Write;

/// One line of a panel: its name in the legend and its (x, y) points (points that are
/// not positive and finite cannot sit on a log axis and are left out).
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// One chart: a title, axis labels and its lines.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

const PANEL_W: f64 = 420.0;
const PANEL_H: f64 = 320.0;
/// Plot area inside a panel: left, top, right, bottom margins (room for labels).
const MARGIN: [f64; 4] = [64.0, 36.0, 16.0, 48.0];
const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf",
];

/// The panels side by side in one SVG document.
pub fn log_log_svg(panels: &[Panel]) -> String {
    let width = PANEL_W * panels.len().max(1) as f64;
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{PANEL_H}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        svg,
        r#"<rect width="{width}" height="{PANEL_H}" fill="white"/>"#
    );
    for (k, panel) in panels.iter().enumerate() {
        draw_panel(&mut svg, panel, k as f64 * PANEL_W);
    }
    svg.push_str("</svg>\n");
    svg
}

/// Whole decades `[lo, hi]` (powers of ten) covering every positive finite value.
fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(libm::log10)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return (0, 1);
    }
    let (lo, hi) = (lo.floor() as i32, hi.ceil() as i32);
    (lo, hi.max(lo + 1))
}

fn plottable(p: &(f64, f64)) -> bool {
    [p.0, p.1].iter().all(|v| v.is_finite() && *v > 0.0)
}

fn draw_panel(svg: &mut String, panel: &Panel, left: f64) {
    let points = || {
        panel
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| plottable(p)))
    };
    let (x0, x1) = decades(points().map(|p| p.0));
    let (y0, y1) = decades(points().map(|p| p.1));
    let [ml, mt, mr, mb] = MARGIN;
    let (w, h) = (PANEL_W - ml - mr, PANEL_H - mt - mb);
    let sx = |x: f64| left + ml + (libm::log10(x) - x0 as f64) / (x1 - x0) as f64 * w;
    let sy = |y: f64| mt + h - (libm::log10(y) - y0 as f64) / (y1 - y0) as f64 * h;
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="13">{}</text>"#,
        left + PANEL_W / 2.0,
        escape(&panel.title)
    );
    let _ = writeln!(
        svg,
        r##"<rect x="{}" y="{mt}" width="{w}" height="{h}" fill="none" stroke="#444"/>"##,
        left + ml
    );
    for d in x0..=x1 {
        let x = sx(10f64.powi(d));
        let _ = writeln!(
            svg,
            r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{}" stroke="#ddd"/><text x="{x:.1}" y="{}" text-anchor="middle">1e{d}</text>"##,
            mt + h,
            mt + h + 14.0
        );
    }
    for d in y0..=y1 {
        let y = sy(10f64.powi(d));
        let _ = writeln!(
            svg,
            r##"<line x1="{}" y1="{y:.1}" x2="{}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">1e{d}</text>"##,
            left + ml,
            left + ml + w,
            left + ml - 4.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        left + ml + w / 2.0,
        PANEL_H - 12.0,
        escape(&panel.x_label)
    );
    let _ = writeln!(
        svg,
        r#"<text transform="translate({},{}) rotate(-90)" text-anchor="middle">{}</text>"#,
        left + 14.0,
        mt + h / 2.0,
        escape(&panel.y_label)
    );
    for (i, series) in panel.series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let xy: Vec<(f64, f64)> = series
            .points
            .iter()
            .filter(|p| plottable(p))
            .map(|&(x, y)| (sx(x), sy(y)))
            .collect();
        let path: Vec<String> = xy.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
            path.join(" ")
        );
        for (x, y) in &xy {
            let _ = writeln!(
                svg,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="{colour}"/>"#
            );
        }
        let ly = mt + 14.0 + 14.0 * i as f64;
        let _ = writeln!(
            svg,
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{colour}" stroke-width="2"/><text x="{}" y="{}">{}</text>"#,
            left + ml + 8.0,
            ly - 4.0,
            left + ml + 24.0,
            ly - 4.0,
            left + ml + 28.0,
            ly,
            escape(&series.name)
        );
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_cover_the_values_and_skip_what_a_log_axis_cannot_show() {
        assert_eq!(
            decades([3.0, 420.0, 0.0, -1.0, f64::NAN].into_iter()),
            (0, 3)
        );
        assert_eq!(decades([1e4, 1e8].into_iter()), (4, 8));
        assert_eq!(decades([5.0].into_iter()), (0, 1));
        assert_eq!(decades(std::iter::empty()), (0, 1));
    }

    #[test]
    fn a_chart_has_one_line_per_series_and_escapes_its_text() {
        let panel = |title: &str| Panel {
            title: title.into(),
            x_label: "triangles".into(),
            y_label: "MiB".into(),
            series: vec![
                Series {
                    name: "a<b".into(),
                    points: vec![(1e4, 24.0), (1e6, 151.0), (1e8, 0.0)],
                },
                Series {
                    name: "c".into(),
                    points: vec![(1e2, 33.0)],
                },
            ],
        };
        let svg = log_log_svg(&[panel("memory"), panel("rate")]);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert_eq!(svg.matches("<polyline").count(), 4);
        // The zero is left out: two markers for the first series, one for the second.
        assert_eq!(svg.matches("<circle").count(), 6);
        assert!(svg.contains("a&lt;b") && !svg.contains("a<b"));
        assert!(svg.contains(r#"width="840""#));
    }
}
