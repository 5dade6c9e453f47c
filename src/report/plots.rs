//! Small SVG charts for the HTML report.
//!
//! Written by hand rather than with a plotting crate: plotters and its
//! peers lay text out with a font backend (system fonts or a bundled TTF),
//! which a headless CI machine may not have, while in SVG the browser lays
//! the text out itself. Line and scatter charts with axes and a legend are
//! all the report needs.

use std::fmt::Write;

/// A named series of (x, y) points.
#[derive(Clone, Debug, Default)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Draw a line through the points (else only markers).
    pub line: bool,
    /// What hovering each point says (its SVG `<title>`), by point; a
    /// point without one says its series and coordinates.
    pub titles: Vec<String>,
    /// A short label drawn beside each point (empty: none).
    pub marks: Vec<String>,
}

/// Whether a chart of `series` carries information: some series has
/// points at two or more x positions.
pub fn informative(series: &[Series]) -> bool {
    series.iter().any(|s| {
        let mut xs: Vec<f64> = s
            .points
            .iter()
            .map(|p| p.0)
            .filter(|x| x.is_finite())
            .collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        xs.len() >= 2
    })
}

/// Twelve colours told apart by eye (ColorBrewer's Paired, reordered so
/// that neighbours differ in hue first): a chart with up to twelve series
/// never repeats one in its legend.
const COLORS: [&str; 12] = [
    "#1f78b4", "#e31a1c", "#33a02c", "#ff7f00", "#6a3d9a", "#b15928", "#a6cee3", "#fb9a99",
    "#b2df8a", "#fdbf6f", "#cab2d6", "#4d4d4d",
];

/// Longest categorical label drawn in full; longer ones are shortened
/// with "…" and said whole when hovered.
const LABEL_CHARS: usize = 28;

/// The vertical range a chart shows for data from `min` to `max`: the data
/// with a twentieth of their range either side, from 0 only when the data
/// come near it (so SSIMs from 0.95 to 0.99 fill the chart instead of its
/// top twentieth).
fn fitted_range(min: f64, max: f64) -> (f64, f64) {
    if !(min.is_finite() && max.is_finite()) || min > max {
        return (0.0, 1.0);
    }
    let span = (max - min).max(max.abs() * 1e-3).max(1e-9);
    let (low, high) = (min - span * 0.05, max + span * 0.05);
    if min >= 0.0 && min < span * 0.5 {
        (0.0, high)
    } else {
        (low, high)
    }
}

/// An SVG chart of `series` with axis labels; `x_labels` names integer x
/// positions when given (a categorical axis).
pub fn chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    x_labels: Option<&[String]>,
) -> String {
    let plot = Plot::new(series, x_labels);
    let (width, height) = (plot.width, plot.height);
    let mut svg = String::new();
    let _ = write!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" width="{width}" height="{height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = write!(
        svg,
        r#"<text x="{}" y="18" text-anchor="middle" font-size="13" font-weight="bold">{}</text>"#,
        width / 2.0,
        escape(title)
    );
    plot.axes(&mut svg, x_labels);
    plot.axis_titles(&mut svg, x_label, y_label);
    for (i, s) in series.iter().enumerate() {
        plot.series(&mut svg, s, COLORS[i % COLORS.len()], i);
    }
    svg.push_str("</svg>");
    svg
}

/// A chart's geometry: its size, the plot's margins (the legend's on the
/// right) and the data ranges the axes span.
struct Plot {
    width: f64,
    height: f64,
    left: f64,
    right: f64,
    top: f64,
    bottom: f64,
    x: (f64, f64),
    y: (f64, f64),
}

impl Plot {
    fn new(series: &[Series], x_labels: Option<&[String]>) -> Plot {
        // The legend has a margin of its own, right of the plot, as wide
        // as its longest name, so that it never covers a point nor is cut
        // off; rotated categorical labels get as much room below as they
        // need.
        let width = 800.0;
        let longest_name = series
            .iter()
            .map(|s| s.name.chars().count())
            .max()
            .unwrap_or(0);
        let longest_label = x_labels
            .map(|labels| {
                labels
                    .iter()
                    .map(|l| l.chars().count().min(LABEL_CHARS + 1))
                    .max()
                    .unwrap_or(0)
            })
            .unwrap_or(0);
        let (left, right, top, bottom) = (
            // The first rotated label reaches left of its category by
            // about cos 40° of its length.
            72f64.max(12.0 + 6.0 * 0.77 * longest_label as f64),
            (40.0 + 6.5 * longest_name as f64).clamp(80.0, 260.0),
            32.0,
            if x_labels.is_some() {
                // 6 px a character at 40°: sin 40° ≈ 0.64 of it below the
                // axis.
                40.0 + 6.0 * 0.64 * longest_label as f64
            } else {
                48.0
            },
        );
        let height = 360.0 + bottom - 48.0;
        let points = series.iter().flat_map(|s| &s.points);
        let (mut x0, mut x1, mut y_min, mut y_max) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in points {
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y_min = y_min.min(y);
                y_max = y_max.max(y);
            }
        }
        if x0 > x1 {
            (x0, x1) = (0.0, 1.0);
        }
        if x1 - x0 < 1e-9 {
            x1 = x0 + 1.0;
        }
        Plot {
            width,
            height,
            left,
            right,
            top,
            bottom,
            x: (x0, x1),
            y: fitted_range(y_min, y_max),
        }
    }

    fn sx(&self, x: f64) -> f64 {
        let (x0, x1) = self.x;
        self.left + (x - x0) / (x1 - x0) * (self.width - self.left - self.right)
    }

    fn sy(&self, y: f64) -> f64 {
        let (y0, y1) = self.y;
        self.height - self.bottom - (y - y0) / (y1 - y0) * (self.height - self.top - self.bottom)
    }

    /// The axes, the y grid and ticks, and the x ticks or category labels.
    fn axes(&self, svg: &mut String, x_labels: Option<&[String]>) {
        let (width, height, left, right, top, bottom) = (
            self.width,
            self.height,
            self.left,
            self.right,
            self.top,
            self.bottom,
        );
        let _ = write!(
            svg,
            r##"<line x1="{left}" y1="{}" x2="{}" y2="{}" stroke="#333"/><line x1="{left}" y1="{top}" x2="{left}" y2="{}" stroke="#333"/>"##,
            height - bottom,
            width - right,
            height - bottom,
            height - bottom
        );
        let (y0, y1) = self.y;
        let y_step = (y1 - y0) / 5.0;
        for i in 0..=5 {
            let y = y0 + y_step * f64::from(i);
            let _ = write!(
                svg,
                r##"<line x1="{left}" y1="{py}" x2="{}" y2="{py}" stroke="#ddd"/><text class="y-tick" x="{}" y="{}" text-anchor="end">{}</text>"##,
                width - right,
                left - 4.0,
                self.sy(y) + 4.0,
                tick(y, y_step),
                py = self.sy(y)
            );
        }
        match x_labels {
            Some(labels) => {
                for (i, label) in labels.iter().enumerate() {
                    let x = self.sx(i as f64);
                    let shown: String = if label.chars().count() > LABEL_CHARS {
                        label.chars().take(LABEL_CHARS).chain(['…']).collect()
                    } else {
                        label.clone()
                    };
                    let _ = write!(
                        svg,
                        r#"<text x="{x}" y="{}" text-anchor="end" transform="rotate(-40 {x} {})"><title>{}</title>{}</text>"#,
                        height - bottom + 14.0,
                        height - bottom + 14.0,
                        escape(label),
                        escape(&shown)
                    );
                }
            }
            None => {
                let (x0, x1) = self.x;
                for i in 0..=5 {
                    let x = x0 + (x1 - x0) * f64::from(i) / 5.0;
                    let _ = write!(
                        svg,
                        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
                        self.sx(x),
                        height - bottom + 14.0,
                        number(x)
                    );
                }
            }
        }
    }

    fn axis_titles(&self, svg: &mut String, x_label: &str, y_label: &str) {
        let (height, top, bottom) = (self.height, self.top, self.bottom);
        let _ = write!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            (self.left + self.width - self.right) / 2.0,
            height - 6.0,
            escape(x_label)
        );
        let _ = write!(
            svg,
            r#"<text x="14" y="{}" text-anchor="middle" transform="rotate(-90 14 {})">{}</text>"#,
            (top + height - bottom) / 2.0,
            (top + height - bottom) / 2.0,
            escape(y_label)
        );
    }

    /// Series `s` (the `index`th) in `color`: its line, its points with
    /// their titles and marks, and its legend entry.
    fn series(&self, svg: &mut String, s: &Series, color: &str, index: usize) {
        let finite: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        if s.line && finite.len() > 1 {
            let path: Vec<String> = finite
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", self.sx(x), self.sy(y)))
                .collect();
            let _ = write!(
                svg,
                r#"<polyline fill="none" stroke="{color}" stroke-width="2" points="{}"/>"#,
                path.join(" ")
            );
        }
        for (j, &(x, y)) in s.points.iter().enumerate() {
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let title = s
                .titles
                .get(j)
                .cloned()
                .unwrap_or_else(|| format!("{}: {}, {}", s.name, number(x), number(y)));
            let _ = write!(
                svg,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{color}"><title>{}</title></circle>"#,
                self.sx(x),
                self.sy(y),
                escape(&title)
            );
            if let Some(mark) = s.marks.get(j).filter(|m| !m.is_empty()) {
                let _ = write!(
                    svg,
                    r#"<text x="{:.1}" y="{:.1}" font-size="9" fill="{color}">{}</text>"#,
                    self.sx(x) + 5.0,
                    self.sy(y) - 5.0,
                    escape(mark)
                );
            }
        }
        let ly = self.top + 4.0 + 14.0 * index as f64;
        let _ = write!(
            svg,
            r#"<rect x="{}" y="{}" width="10" height="10" fill="{color}"/><text x="{}" y="{}">{}</text>"#,
            self.width - self.right + 12.0,
            ly,
            self.width - self.right + 26.0,
            ly + 9.0,
            escape(&s.name)
        );
    }
}

/// A tick's value with as many decimals as ticks `step` apart need to
/// differ (SSIM ticks 0.002 apart read 0.9950, 0.9970, not 0.995 twice).
fn tick(v: f64, step: f64) -> String {
    let decimals = if step > 0.0 && step.is_finite() {
        (1.0 - step.log10().floor()).clamp(0.0, 6.0) as usize
    } else {
        2
    };
    format!("{v:.decimals$}")
}

fn number(v: f64) -> String {
    if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vertical_range_fits_the_data() {
        // SSIMs near 1 fill the chart instead of its top twentieth.
        let (low, high) = fitted_range(0.95, 0.99);
        assert!(
            low > 0.94 && low < 0.95 && high > 0.99 && high < 1.0,
            "{low} {high}"
        );
        // Data that come near 0 start at 0.
        assert_eq!(fitted_range(0.1, 10.0).0, 0.0);
        // Negative data keep their sign.
        assert!(fitted_range(-2.0, 3.0).0 < -2.0);
        // Ticks say apart what they are apart.
        assert_ne!(tick(0.9950, 0.002), tick(0.9970, 0.002));
    }

    #[test]
    fn a_knob_at_one_value_is_not_informative() {
        let one = Series {
            name: "k = 4".into(),
            points: vec![(32.0, 1.1), (32.0, 1.2)],
            ..Series::default()
        };
        assert!(!informative(std::slice::from_ref(&one)));
        let two = Series {
            points: vec![(16.0, 1.0), (32.0, 1.2)],
            ..one
        };
        assert!(informative(&[two]));
    }

    #[test]
    fn points_say_what_they_are_and_the_legend_keeps_off_the_data() {
        let series = Series {
            name: "two-pass".into(),
            points: vec![(1.0, 30.0), (2.0, 35.0)],
            titles: vec![
                "#1 n1 two-pass, Δn = 32".into(),
                "#2 n1 two-pass, Δn = 8".into(),
            ],
            marks: vec!["#1".into(), String::new()],
            ..Series::default()
        };
        let svg = chart("PSNR against time", "ms", "dB", &[series], None);
        assert!(
            svg.contains("<title>#1 n1 two-pass, Δn = 32</title>"),
            "{svg}"
        );
        assert!(svg.contains(">#1</text>"));
        // The legend's swatch lies right of the plot area's right edge
        // (12 px right of it; the margin is as wide as the names).
        let swatch = svg.find("<rect x=\"").unwrap() + "<rect x=\"".len();
        let x: f64 = svg[swatch..].split('"').next().unwrap().parse().unwrap();
        let plot_right = x - 12.0;
        assert!(plot_right > 600.0, "{x}");
        // No point is drawn right of the plot area.
        for cx in svg.split("<circle cx=\"").skip(1) {
            let cx: f64 = cx.split('"').next().unwrap().parse().unwrap();
            assert!(cx <= plot_right + 1e-6);
        }
    }
}
