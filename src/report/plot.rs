//! The SVG plot of a sweep: relMSE against seconds, log-log, one line per method (the mean
//! over repetitions at each budget) with every repetition as a dot and the repetitions'
//! spread as a bar, a tick at every budget; below it, each method's relMSE over the
//! baseline's (`pg`'s, else `pt`'s) at equal time; the legend, beside the data, gives each
//! method's median efficiency `1/(relMSE × seconds)`. The main plot shows the methods; a
//! sweep's ablations (labels with settings, `ga-pt:cw=0`) get a plot of their own.

use super::Row;
use plotters::prelude::*;

/// Per method, in first-seen order: its rows.
fn by_method(rows: &[Row]) -> Vec<(&str, Vec<&Row>)> {
    let mut out: Vec<(&str, Vec<&Row>)> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(m, _)| *m == r.method) {
            Some((_, v)) => v.push(r),
            None => out.push((&r.method, vec![r])),
        }
    }
    out
}

/// Median of the finite values (NaN when there are none).
pub fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Means over the repetitions at one budget.
#[derive(Clone, Copy, Debug)]
pub struct Mean {
    pub budget: f64,
    pub spp: f64,
    pub seconds: f64,
    pub relmse: f64,
}

/// Per budget, by increasing budget: the means of `rows` (one method's).
pub fn means(rows: &[&Row]) -> Vec<Mean> {
    let mut budgets: Vec<f64> = rows.iter().map(|r| r.budget).collect();
    budgets.sort_by(f64::total_cmp);
    budgets.dedup();
    budgets
        .iter()
        .map(|&budget| {
            let at: Vec<_> = rows.iter().filter(|r| r.budget == budget).collect();
            let n = at.len() as f64;
            let mean = |f: fn(&Row) -> f64| at.iter().map(|r| f(r)).sum::<f64>() / n;
            Mean {
                budget,
                spp: mean(|r| f64::from(r.spp)),
                seconds: mean(|r| r.seconds),
                relmse: mean(|r| r.relmse),
            }
        })
        .collect()
}

/// Whether a method label names an ablation (a method with settings, `ga-pt:cw=0`).
pub fn is_ablation(label: &str) -> bool {
    label.contains(':')
}

/// The method the ratio panel divides by: `pg` if the rows have it, else `pt`.
fn baseline(rows: &[Row]) -> Option<&'static str> {
    ["pg", "pt"]
        .into_iter()
        .find(|b| rows.iter().any(|r| r.method == *b))
}

/// A method's colour: fixed for the methods, from a palette for the rest.
fn colour(method: &str, i: usize) -> RGBAColor {
    match method {
        "pt" => BLACK.to_rgba(),
        "pg" => RGBColor(31, 100, 200).to_rgba(),
        "ga-pt" => RGBColor(214, 39, 40).to_rgba(),
        "ga" => RGBColor(44, 160, 44).to_rgba(),
        "srt" => RGBColor(255, 127, 14).to_rgba(),
        _ => {
            const OTHERS: [RGBColor; 6] = [
                RGBColor(148, 103, 189),
                RGBColor(140, 86, 75),
                RGBColor(227, 119, 194),
                RGBColor(127, 127, 127),
                RGBColor(188, 189, 34),
                RGBColor(23, 190, 207),
            ];
            OTHERS[i % OTHERS.len()].to_rgba()
        }
    }
}

/// Why the plot was not drawn: the plotting library's error, as its text (its type depends
/// on the drawing back-end).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cannot draw the plot: {0}")]
pub struct PlotError(String);

/// The plot of `rows` as SVG text: of the methods only, or with `ablations` of every row;
/// with `time` budgets (seconds), a tick at every budget.
pub fn svg(title: &str, rows: &[Row], ablations: bool, time: bool) -> Result<String, PlotError> {
    let rows: Vec<Row> = rows
        .iter()
        .filter(|r| ablations || !is_ablation(&r.method))
        .cloned()
        .collect();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (1000, 760)).into_drawing_area();
        draw(&root, title, &rows, time).map_err(|e| PlotError(e.to_string()))?;
        root.present().map_err(|e| PlotError(e.to_string()))?;
    }
    Ok(text)
}

/// Ticks at 1, 2 and 5 times the powers of ten between `lo` and `hi` (and at 1.5, 3 and 7
/// too where the range is under two decades).
fn round_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let steps: &[f64] = if hi / lo < 100.0 {
        &[1.0, 1.5, 2.0, 3.0, 5.0, 7.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi && ticks.len() < 64 {
        ticks.extend(
            steps
                .iter()
                .map(|m| m * decade)
                .filter(|t| (lo..=hi).contains(t)),
        );
        decade *= 10.0;
    }
    ticks
}

/// A tick's value without trailing zeros: 2, 0.5, 30.
fn tick_label(x: f64) -> String {
    let text = format!("{x:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn usable(r: &Row) -> bool {
    r.relmse.is_finite() && r.relmse > 0.0 && r.seconds > 0.0
}

/// `(lo, hi)` of `values` widened by `pad` on a log scale, or `fallback`.
fn log_range(values: impl Iterator<Item = f64>, pad: f64, fallback: (f64, f64)) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    if lo.is_finite() && hi > 0.0 {
        (lo / pad, hi * pad)
    } else {
        fallback
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    rows: &[Row],
    time: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 22))?;
    let (plots, legend) = root.split_horizontally(760);
    let (top, bottom) = plots.split_vertically(460);
    let methods = by_method(rows);
    let good: Vec<&Row> = rows.iter().filter(|r| usable(r)).collect();
    let (x0, x1) = log_range(good.iter().map(|r| r.seconds), 1.3, (0.1, 10.0));
    let (y0, y1) = log_range(good.iter().map(|r| r.relmse), 1.5, (0.1, 10.0));
    let ticks = if time {
        let mut budgets: Vec<f64> = rows.iter().map(|r| r.budget).collect();
        budgets.sort_by(f64::total_cmp);
        budgets.dedup();
        budgets
    } else {
        round_ticks(x0, x1)
    };
    let x_axis = || (x0..x1).log_scale().with_key_points(ticks.clone());
    let x_range = (x0, x1);
    let mut chart = ChartBuilder::on(&top)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(72)
        .build_cartesian_2d(
            x_axis(),
            (y0..y1).log_scale().with_key_points(round_ticks(y0, y1)),
        )?;
    chart
        .configure_mesh()
        .x_desc("seconds (all phases)")
        .y_desc("relMSE")
        .x_label_formatter(&|x| tick_label(*x))
        .y_label_formatter(&|y| format!("{y:.1e}"))
        .light_line_style(TRANSPARENT)
        .draw()?;
    for (i, (method, rows)) in methods.iter().enumerate() {
        let c = colour(method, i);
        let line: Vec<(f64, f64)> = means(rows)
            .into_iter()
            .filter(|m| m.seconds > 0.0 && m.relmse > 0.0 && m.relmse.is_finite())
            .map(|m| (m.seconds, m.relmse))
            .collect();
        chart.draw_series(LineSeries::new(line, c.stroke_width(2)))?;
        chart.draw_series(
            rows.iter()
                .filter(|r| usable(r))
                .map(|r| Circle::new((r.seconds, r.relmse), 3, c.filled())),
        )?;
        // The repetitions' spread at each budget: a bar from the least to the most relMSE.
        for m in means(rows) {
            let at: Vec<f64> = rows
                .iter()
                .filter(|r| r.budget == m.budget && usable(r))
                .map(|r| r.relmse)
                .collect();
            if at.len() > 1 && m.seconds > 0.0 {
                let lo = at.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = at.iter().copied().fold(0.0, f64::max);
                let bar = vec![(m.seconds, lo), (m.seconds, hi)];
                chart.draw_series(std::iter::once(PathElement::new(bar, c.stroke_width(1))))?;
            }
        }
    }
    draw_ratios(&bottom, rows, &methods, x_range, &ticks)?;
    draw_legend(&legend, &methods)
}

/// Each method's relMSE over the baseline's at equal time (`relMSE × seconds` over the
/// baseline's, mean over repetitions at each budget), against seconds.
fn draw_ratios<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    rows: &[Row],
    methods: &[(&str, Vec<&Row>)],
    (x0, x1): (f64, f64),
    ticks: &[f64],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let Some(base) = baseline(rows) else {
        return Ok(());
    };
    let base_means = means(&rows.iter().filter(|r| r.method == base).collect::<Vec<_>>());
    let ratios: Vec<(usize, Vec<(f64, f64)>)> = methods
        .iter()
        .enumerate()
        .map(|(i, (_, of))| {
            let points = means(of)
                .into_iter()
                .filter_map(|m| {
                    let b = base_means.iter().find(|b| b.budget == m.budget)?;
                    let ratio = (m.relmse * m.seconds) / (b.relmse * b.seconds);
                    (ratio.is_finite() && ratio > 0.0 && m.seconds > 0.0)
                        .then_some((m.seconds, ratio))
                })
                .collect();
            (i, points)
        })
        .collect();
    let (r0, r1) = log_range(
        ratios
            .iter()
            .flat_map(|(_, p)| p.iter().map(|&(_, r)| r))
            .chain([1.0]),
        1.3,
        (0.5, 2.0),
    );
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(ticks.to_vec()),
            (r0..r1).log_scale().with_key_points(round_ticks(r0, r1)),
        )?;
    chart
        .configure_mesh()
        .x_desc("seconds (all phases)")
        .y_desc(format!("relMSE over {base}'s, equal time"))
        .x_label_formatter(&|x| tick_label(*x))
        .y_label_formatter(&|y| tick_label(*y))
        .light_line_style(TRANSPARENT)
        .draw()?;
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(x0, 1.0), (x1, 1.0)],
        BLACK.mix(0.4).stroke_width(1),
    )))?;
    for (i, points) in ratios {
        let c = colour(methods[i].0, i);
        chart.draw_series(LineSeries::new(points.clone(), c.stroke_width(2)))?;
        chart.draw_series(points.into_iter().map(|p| Circle::new(p, 3, c.filled())))?;
    }
    Ok(())
}

/// The legend, beside the plots: each method's colour, name and median efficiency.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    methods: &[(&str, Vec<&Row>)],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let style = ("sans-serif", 14).into_font();
    area.draw(&Text::new(
        "method (median efficiency",
        (8, 20),
        style.clone(),
    ))?;
    area.draw(&Text::new(
        "1 / (relMSE × seconds))",
        (8, 38),
        style.clone(),
    ))?;
    for (i, (method, rows)) in methods.iter().enumerate() {
        let y = 70 + 24 * i as i32;
        let c = colour(method, i);
        area.draw(&PathElement::new(vec![(8, y), (36, y)], c.stroke_width(3)))?;
        let efficiency = median(rows.iter().map(|r| r.efficiency()));
        let label = format!("{method} ({efficiency:.3})");
        area.draw(&Text::new(label, (44, y - 8), style.clone()))?;
    }
    Ok(())
}
