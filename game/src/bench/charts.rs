//! PNG charts drawn with plotters into an RGB buffer (saved with `image`). Text uses the DejaVu Sans font
//! shipped in assets/fonts through plotters' ab_glyph path: no system fonts or fontconfig needed.

use super::bvh_quality::{PresetRow, RefitResult};
use super::error_curves::SceneErrors;
use super::frame_loop::FrameRow;
use super::scaling::{ResolutionScalingRow, TriangleScalingRow};
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
const SANS: &str = "sans-serif";

/// Tableau 10: distinct on white, and in the same order in every chart.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn color(i: usize) -> RGBColor {
    COLORS[i % COLORS.len()]
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// What a chart shows (first line) and where it was measured (second line: adapter, suite, commit, date).
pub struct Title {
    pub what: String,
    pub context: String,
}

/// Draws into a white `size` canvas with the two-line title on top, then writes `path` as PNG.
fn draw_png(
    path: &Path,
    size: (u32, u32),
    title: &Title,
    draw: impl FnOnce(&Area) -> Result<()>,
) -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(SANS, FontStyle::Normal, FONT).is_ok());
    anyhow::ensure!(
        ok,
        "the chart font (assets/fonts/DejaVuSans.ttf) did not load"
    );
    let mut buffer = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
        root.fill(&WHITE)?;
        let body = root.titled(&title.what, (SANS, 20))?.titled(
            &title.context,
            (SANS, 13).into_font().color(&BLACK.mix(0.6)),
        )?;
        draw(&body)?;
        root.present()?;
    }
    let image = image::RgbImage::from_raw(size.0, size.1, buffer)
        .context("chart buffer size does not match the canvas")?;
    image
        .save_with_format(path, image::ImageFormat::Png)
        .with_context(|| format!("{}: cannot write the chart", path.display()))
}

/// A log axis range covering `values` (positive, finite ones), padded a little.
fn log_range(values: impl IntoIterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return 0.1..10.0;
    }
    let (lo, hi) = if hi / lo < 4.0 {
        (lo / 2.0, hi * 2.0)
    } else {
        (lo / 1.3, hi * 1.3)
    };
    lo..hi
}

fn fmt_num(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

fn legend(series_color: RGBColor) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], series_color.stroke_width(3))
}

type LogX<Y> =
    plotters::coord::cartesian::Cartesian2d<plotters::coord::combinators::LogCoord<f64>, Y>;

/// Grid, tick labels and axis names of a chart with a log x axis (y log or linear).
fn log_x_axes<'a, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, LogX<Y>>,
    x_desc: &str,
    y_desc: &str,
) -> Result<()>
where
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>
        + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&fmt_num)
        .y_label_formatter(&fmt_num)
        .x_labels(14)
        .y_labels(12)
        .label_style((SANS, 13))
        .draw()?;
    Ok(())
}

/// The series legend, boxed, in one style for every chart.
fn draw_legend<'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    position: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((SANS, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .draw()?;
    Ok(())
}

/// Error vs trace time for one scene: relMSE (left) and FLIP (right), one line per setting.
pub fn error_vs_time(path: &Path, title: &Title, errors: &SceneErrors) -> Result<()> {
    draw_png(path, (1500, 620), title, |area| {
        let panels = area.split_evenly((1, 2));
        let times = || {
            errors
                .curves
                .iter()
                .flat_map(|c| c.points.iter().map(|p| p.time_ms))
        };
        for (panel, metric) in panels.iter().zip(["relMSE", "FLIP"]) {
            let value = |p: &super::error_curves::CurvePoint| {
                if metric == "FLIP" { p.flip } else { p.rel_mse }
            };
            let values = errors
                .curves
                .iter()
                .flat_map(|c| c.points.iter().map(value));
            let mut chart = ChartBuilder::on(panel)
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .caption(
                    format!("{metric} vs {} trace time", errors.timing_source),
                    (SANS, 16),
                )
                .build_cartesian_2d(
                    log_range(times()).log_scale(),
                    log_range(values).log_scale(),
                )?;
            log_x_axes(
                &mut chart,
                "trace time (ms, cumulative)",
                if metric == "FLIP" {
                    "mean FLIP (tone-mapped)"
                } else {
                    "relMSE (tone-mapped)"
                },
            )?;
            for (i, c) in errors.curves.iter().enumerate() {
                let points: Vec<(f64, f64)> =
                    c.points.iter().map(|p| (p.time_ms, value(p))).collect();
                let col = color(i);
                chart
                    .draw_series(LineSeries::new(points.clone(), col.stroke_width(2)))?
                    .label(c.name.as_str())
                    .legend(legend(col));
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, col.filled())))?;
            }
            if metric == "relMSE" {
                for target in [0.01, 0.001] {
                    let x = chart.x_range();
                    chart.draw_series(LineSeries::new(
                        [(x.start, target), (x.end, target)],
                        BLACK.mix(0.25).stroke_width(1),
                    ))?;
                }
                draw_legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
            }
        }
        Ok(())
    })
}

/// Build time against trace time for each obvhs preset, one series per scene.
pub fn bvh_presets(path: &Path, title: &Title, rows: &[PresetRow]) -> Result<()> {
    draw_png(path, (1100, 640), title, |area| {
        let mut chart = ChartBuilder::on(area)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                log_range(rows.iter().map(|r| r.build_ms)).log_scale(),
                // Linear from 0: the presets differ by tens of percent, too little for log-axis labels.
                0.0..rows.iter().map(|r| r.trace_ms.min).fold(0.0, f64::max) * 1.15,
            )?;
        log_x_axes(
            &mut chart,
            "BLAS build ms (all meshes, one thread)",
            "trace ms per frame (fastest frame)",
        )?;
        let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
        scenes.dedup();
        for (i, scene) in scenes.iter().enumerate() {
            let col = color(i);
            let mut points: Vec<&PresetRow> = rows.iter().filter(|r| r.scene == *scene).collect();
            points.sort_by(|a, b| a.build_ms.total_cmp(&b.build_ms));
            chart
                .draw_series(LineSeries::new(
                    points.iter().map(|r| (r.build_ms, r.trace_ms.min)),
                    col.mix(0.5).stroke_width(1),
                ))?
                .label(format!("{scene} ({} triangles)", points[0].triangles))
                .legend(legend(col));
            chart.draw_series(points.iter().map(|r| {
                EmptyElement::at((r.build_ms, r.trace_ms.min))
                    + Circle::new((0, 0), 4, col.filled())
                    + Text::new(format!("{:?}", r.preset), (6, -14), (SANS, 12))
            }))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// Refit against rebuild along an animation: SAH ratio, trace ms with each tree, update ms of each.
pub fn refit_vs_rebuild(path: &Path, title: &Title, r: &RefitResult) -> Result<()> {
    draw_png(path, (1100, 1000), title, |area| {
        let panels = area.split_evenly((3, 1));
        let t_end = r.frames.last().map_or(1.0, |f| f.time_s as f64).max(1e-3);
        type Series<'s> = Vec<(&'s str, Vec<(f64, f64)>)>;
        let series = |f: fn(&super::bvh_quality::RefitFrame) -> f64| -> Vec<(f64, f64)> {
            r.frames
                .iter()
                .map(|fr| (fr.time_s as f64, f(fr)))
                .collect()
        };
        let plots: [(&str, Series, bool); 3] = [
            (
                "SAH cost of the refit tree / its cost at build",
                vec![("refit only", series(|f| f.sah_ratio_refit as f64))],
                false,
            ),
            (
                "trace ms of the same pose (fastest of the repeated frames)",
                vec![
                    ("refit tree", series(|f| f.trace_ms_refit)),
                    ("rebuilt tree", series(|f| f.trace_ms_rebuilt)),
                ],
                false,
            ),
            (
                "BVH update ms (CPU)",
                vec![
                    ("refit", series(|f| f.refit_ms)),
                    ("full rebuild", series(|f| f.rebuild_ms)),
                ],
                true,
            ),
        ];
        for (panel, (label, lines, log_y)) in panels.iter().zip(plots) {
            let values: Vec<f64> = lines.iter().flat_map(|l| l.1.iter().map(|p| p.1)).collect();
            let mut builder = ChartBuilder::on(panel);
            builder
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .caption(label, (SANS, 15));
            let range = log_range(values.iter().copied());
            macro_rules! plot {
                ($chart:expr) => {{
                    let mut chart = $chart;
                    chart
                        .configure_mesh()
                        .x_desc("animation time (s)")
                        .y_label_formatter(&fmt_num)
                        .x_labels(14)
                        .y_labels(12)
                        .label_style((SANS, 13))
                        .draw()?;
                    for (i, (name, points)) in lines.iter().enumerate() {
                        let col = color(i);
                        chart
                            .draw_series(LineSeries::new(points.clone(), col.stroke_width(2)))?
                            .label(*name)
                            .legend(legend(col));
                    }
                    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
                }};
            }
            if log_y {
                plot!(builder.build_cartesian_2d(0.0..t_end, range.log_scale())?);
            } else {
                let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = values.iter().copied().fold(0.0, f64::max);
                let pad = ((hi - lo) * 0.1).max(hi * 0.02).max(1e-6);
                plot!(builder.build_cartesian_2d(0.0..t_end, (lo - pad).max(0.0)..hi + pad)?);
            }
        }
        Ok(())
    })
}

/// Stacked bars: median ms of each pass per (scene, size).
pub fn frame_breakdown(path: &Path, title: &Title, rows: &[FrameRow]) -> Result<()> {
    anyhow::ensure!(!rows.is_empty(), "no frame-loop rows to chart");
    let width = (420 + 120 * rows.len() as u32).max(900);
    draw_png(path, (width, 680), title, |area| {
        let (plot, key) = area.split_horizontally(width - 260);
        let top = rows
            .iter()
            .map(|r| r.passes_median_ms.total())
            .fold(0.0, f64::max)
            .max(1e-3)
            * 1.08;
        let labels: Vec<String> = rows
            .iter()
            .map(|r| format!("{} {}x{}", r.scene, r.width, r.height))
            .collect();
        let mut chart = ChartBuilder::on(&plot)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((0..rows.len().saturating_sub(1)).into_segmented(), 0.0..top)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_desc("ms per frame (median)")
            .x_labels(rows.len())
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels.get(*i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .y_label_formatter(&fmt_num)
            .label_style((SANS, 12))
            .draw()?;
        let parts = rows[0].passes_median_ms.parts();
        for (k, (name, _)) in parts.iter().enumerate() {
            let col = color(k);
            chart.draw_series(rows.iter().enumerate().map(|(i, r)| {
                let p = r.passes_median_ms.parts();
                let below: f64 = p[..k].iter().map(|x| x.1.max(0.0)).sum();
                let value = if p[k].1.is_finite() {
                    p[k].1.max(0.0)
                } else {
                    0.0
                };
                let mut bar = Rectangle::new(
                    [
                        (SegmentValue::Exact(i), below),
                        (SegmentValue::Exact(i + 1), below + value),
                    ],
                    col.filled(),
                );
                bar.set_margin(0, 0, 14, 14);
                bar
            }))?;
            let y = 30 + 26 * k as i32;
            key.draw(&Rectangle::new([(10, y), (28, y + 16)], col.filled()))?;
            key.draw(&Text::new(name.to_string(), (36, y), (SANS, 14)))?;
        }
        for (i, r) in rows.iter().enumerate() {
            let total = r.passes_median_ms.total();
            chart.draw_series(std::iter::once(Text::new(
                format!("{total:.2} ms"),
                (SegmentValue::CenterOf(i), total + top * 0.01),
                (SANS, 12),
            )))?;
        }
        Ok(())
    })
}

/// Trace time against instanced triangle count (left) and against pixel count (right), log-log.
pub fn scaling(
    path: &Path,
    title: &Title,
    triangles: &[TriangleScalingRow],
    resolution: &[ResolutionScalingRow],
) -> Result<()> {
    draw_png(path, (1500, 620), title, |area| {
        let panels = area.split_evenly((1, 2));
        let tri: Vec<(f64, f64, String)> = triangles
            .iter()
            .map(|r| {
                (
                    r.instanced_triangles as f64,
                    r.trace_ms.median,
                    format!("{} copies", r.copies),
                )
            })
            .collect();
        let res: Vec<(f64, f64, String)> = resolution
            .iter()
            .map(|r| {
                (
                    r.width as f64 * r.height as f64,
                    r.trace_ms.median,
                    format!("{}x{}", r.width, r.height),
                )
            })
            .collect();
        let captions = [
            (
                format!(
                    "instanced copies of DamagedHelmet ({} triangles, one BLAS)",
                    triangles.first().map_or(0, |r| r.unique_triangles)
                ),
                "triangles in the scene (instanced)",
            ),
            (
                format!(
                    "{} at several sizes",
                    resolution.first().map_or("", |r| r.scene.as_str())
                ),
                "pixels",
            ),
        ];
        for ((panel, data), (caption, x_desc)) in panels.iter().zip([tri, res]).zip(captions) {
            let mut chart = ChartBuilder::on(panel)
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .caption(caption, (SANS, 15))
                .build_cartesian_2d(
                    log_range(data.iter().map(|p| p.0)).log_scale(),
                    log_range(data.iter().map(|p| p.1)).log_scale(),
                )?;
            log_x_axes(&mut chart, x_desc, "trace ms per frame (median)")?;
            let col = color(0);
            chart.draw_series(LineSeries::new(
                data.iter().map(|p| (p.0, p.1)),
                col.stroke_width(2),
            ))?;
            chart.draw_series(data.iter().map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Circle::new((0, 0), 4, col.filled())
                    + Text::new(p.2.clone(), (6, -14), (SANS, 12))
            }))?;
        }
        Ok(())
    })
}

/// The real-time path in motion, one scene: the displayed frame's relMSE against the frame index (warm-up and
/// the lamp switch visible), and each method's settled error against its GPU time per frame.
pub fn motion(path: &Path, title: &Title, m: &super::motion::MotionScene) -> Result<()> {
    draw_png(path, (1500, 620), title, |area| {
        let panels = area.split_evenly((1, 2));
        let errors = || {
            m.curves
                .iter()
                .flat_map(|c| c.points.iter().map(|p| p.rel_mse))
        };
        let mut chart = ChartBuilder::on(&panels[0])
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .caption("relMSE of the displayed frame vs frame", (SANS, 16))
            .build_cartesian_2d(0.0..m.frames as f64, log_range(errors()).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(format!("frame (dt {:.4} s)", m.dt))
            .y_desc("relMSE (tone-mapped) vs converged pose")
            .x_label_formatter(&fmt_num)
            .y_label_formatter(&fmt_num)
            .label_style((SANS, 13))
            .draw()?;
        for (i, c) in m.curves.iter().enumerate() {
            let col = color(i);
            let points: Vec<(f64, f64)> = c
                .points
                .iter()
                .map(|p| (p.frame as f64, p.rel_mse))
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), col.stroke_width(2)))?
                .label(c.method.as_str())
                .legend(legend(col));
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, col.filled())))?;
        }
        if let Some(k0) = m
            .curves
            .iter()
            .find_map(|c| c.lag.as_ref().map(|l| l.switch_frame))
        {
            let y = chart.y_range();
            chart.draw_series(LineSeries::new(
                [(k0 as f64, y.start), (k0 as f64, y.end)],
                BLACK.mix(0.4).stroke_width(1),
            ))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;

        let times = || m.curves.iter().map(|c| c.gpu_ms.median);
        let steady = || m.curves.iter().map(|c| c.steady_rel_mse);
        let mut chart = ChartBuilder::on(&panels[1])
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .caption("settled relMSE vs GPU time per frame", (SANS, 16))
            .build_cartesian_2d(
                log_range(times()).log_scale(),
                log_range(steady()).log_scale(),
            )?;
        log_x_axes(
            &mut chart,
            "GPU ms per frame (every pass, median)",
            "relMSE (tone-mapped), mean from K/4",
        )?;
        for (i, c) in m.curves.iter().enumerate() {
            let col = color(i);
            chart
                .draw_series([EmptyElement::at((c.gpu_ms.median, c.steady_rel_mse))
                    + Circle::new((0, 0), 5, col.filled())
                    + Text::new(c.method.clone(), (8, -14), (SANS, 12))])?
                .label(c.method.as_str())
                .legend(legend(col));
        }
        Ok(())
    })
}
