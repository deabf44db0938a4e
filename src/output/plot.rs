//! Small SVG line charts for benchmark results, written by hand so the
//! tool needs no plotting library.

use std::fmt::Write;

/// One line of a chart: a name and (x, y) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A line chart. X positions are categorical unless `x_axis` says
/// otherwise: each distinct x gets an equal slot (shading levels 0, 4, 16,
/// 64 would crowd a linear axis).
pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// Y axis range.
    pub y_range: (f64, f64),
    pub series: &'a [Series],
    pub x_axis: XAxis,
}

/// How x values are placed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum XAxis {
    /// Each distinct x its own equal slot, each labelled.
    #[default]
    Slots,
    /// Proportional over the range, six labelled ticks (time series).
    Linear,
}

const COLORS: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

impl Chart<'_> {
    pub fn to_svg(&self) -> String {
        let (w, h) = (640.0, 400.0);
        let (left, right, top, bottom) = (70.0, 150.0, 40.0, 60.0);
        let (pw, ph) = (w - left - right, h - top - bottom);
        let mut xs: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        let (x_lo, x_hi) = (
            xs.first().copied().unwrap_or(0.0),
            xs.last().copied().unwrap_or(1.0),
        );
        let slot = |x: f64| match self.x_axis {
            XAxis::Slots => {
                let i = xs.iter().position(|v| *v == x).unwrap_or(0) as f64;
                left + pw * (i + 0.5) / xs.len().max(1) as f64
            }
            XAxis::Linear if x_hi > x_lo => left + pw * (x - x_lo) / (x_hi - x_lo),
            XAxis::Linear => left + 0.5 * pw,
        };
        let mut ticks = xs.clone();
        if self.x_axis == XAxis::Linear {
            ticks = (0..=5)
                .map(|k| x_lo + (x_hi - x_lo) * f64::from(k) / 5.0)
                .collect();
            ticks.dedup();
        }
        let (y0, y1) = self.y_range;
        let y_of = |y: f64| top + ph * (1.0 - (y - y0) / (y1 - y0));
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(svg, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
            left + pw / 2.0,
            escape(self.title)
        );
        for k in 0..=5 {
            let y = y0 + (y1 - y0) * f64::from(k) / 5.0;
            let py = y_of(y);
            let _ = writeln!(
                svg,
                r##"<line x1="{left}" y1="{py:.1}" x2="{}" y2="{py:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
                left + pw,
                left - 6.0,
                py + 4.0,
                trim(y)
            );
        }
        for &x in &ticks {
            let _ = writeln!(
                svg,
                r#"<text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#,
                slot(x),
                top + ph + 18.0,
                trim(x)
            );
        }
        let _ = writeln!(
            svg,
            r#"<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            left + pw / 2.0,
            h - 18.0,
            escape(self.x_label)
        );
        let _ = writeln!(
            svg,
            r#"<text transform="translate(20 {}) rotate(-90)" text-anchor="middle">{}</text>"#,
            top + ph / 2.0,
            escape(self.y_label)
        );
        for (i, s) in self.series.iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            let radius = if self.x_axis == XAxis::Linear {
                2.0
            } else {
                3.5
            };
            let points: Vec<String> = s
                .points
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", slot(x), y_of(y)))
                .collect();
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2"/>"#,
                points.join(" ")
            );
            for p in &points {
                let (x, y) = p.split_once(',').unwrap_or(("0", "0"));
                let _ = writeln!(
                    svg,
                    r#"<circle cx="{x}" cy="{y}" r="{radius}" fill="{color}"/>"#
                );
            }
            let ly = top + 10.0 + 18.0 * i as f64;
            let _ = writeln!(
                svg,
                r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2"/><text x="{}" y="{}">{}</text>"#,
                left + pw + 12.0,
                left + pw + 32.0,
                left + pw + 38.0,
                ly + 4.0,
                escape(&s.name)
            );
        }
        svg.push_str("</svg>\n");
        svg
    }
}

fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_series_is_drawn_and_labelled() {
        let series = [
            Series {
                name: "cthead".into(),
                points: vec![(0.0, 10.0), (4.0, 40.0), (64.0, 70.0)],
            },
            Series {
                name: "a<b".into(),
                points: vec![(0.0, -5.0), (64.0, 20.0)],
            },
        ];
        let svg = Chart {
            title: "V",
            x_label: "samples",
            y_label: "%",
            y_range: (-10.0, 100.0),
            series: &series,
            x_axis: XAxis::Slots,
        }
        .to_svg();
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 5);
        assert!(svg.contains(">cthead<") && svg.contains(">a&lt;b<"));
        // Three distinct x values, three evenly spaced slots: 0 at the first.
        assert!(svg.contains(">64<") && svg.contains(">4<"));
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
    }

    #[test]
    fn a_linear_axis_places_points_by_value() {
        let series = [Series {
            name: "front".into(),
            points: vec![(0.0, 0.0), (1.0, 1.0), (10.0, 1.0)],
        }];
        let svg = Chart {
            title: "t",
            x_label: "s",
            y_label: "y",
            y_range: (0.0, 1.0),
            series: &series,
            x_axis: XAxis::Linear,
        }
        .to_svg();
        // Plot area from x = 70 to 490: 0 at 70, 1 at 112, 10 at 490.
        assert!(
            svg.contains(r#"points="70.0,340.0 112.0,40.0 490.0,40.0""#),
            "{svg}"
        );
        // Ticks at 0, 2, ..., 10, not one per point.
        assert!(svg.contains(">6<") && svg.contains(">10<") && !svg.contains(">5<"));
    }
}
