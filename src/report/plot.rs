//! The SVG plot of a sweep: relMSE against seconds, log-log, one line per method (the mean
//! over repetitions at each budget) with every repetition as a dot; the legend gives each
//! method's median efficiency `1/(relMSE × seconds)`.

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

/// The plot as SVG text.
pub fn svg(title: &str, rows: &[Row]) -> Result<String, String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (900, 600)).into_drawing_area();
        draw(&root, title, rows).map_err(|e| format!("cannot draw the plot: {e}"))?;
        root.present()
            .map_err(|e| format!("cannot draw the plot: {e}"))?;
    }
    Ok(text)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    rows: &[Row],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let good: Vec<&Row> = rows
        .iter()
        .filter(|r| r.relmse.is_finite() && r.relmse > 0.0 && r.seconds > 0.0)
        .collect();
    let range = |f: fn(&Row) -> f64| {
        let (lo, hi) = good
            .iter()
            .map(|r| f(r))
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            });
        if lo.is_finite() && hi > 0.0 {
            (lo / 1.5, hi * 1.5)
        } else {
            (0.1, 10.0)
        }
    };
    let (x0, x1) = range(|r| r.seconds);
    let (y0, y1) = range(|r| r.relmse);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("seconds (all phases)")
        .y_desc("relMSE")
        .draw()?;
    for (i, (method, rows)) in by_method(rows).into_iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let efficiency = median(rows.iter().map(|r| r.efficiency()));
        let line: Vec<(f64, f64)> = means(&rows)
            .into_iter()
            .filter(|m| m.seconds > 0.0 && m.relmse > 0.0 && m.relmse.is_finite())
            .map(|m| (m.seconds, m.relmse))
            .collect();
        chart
            .draw_series(LineSeries::new(line, colour.stroke_width(2)))?
            .label(format!("{method}  (efficiency {efficiency:.3})"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        chart.draw_series(
            rows.iter()
                .filter(|r| r.relmse > 0.0 && r.relmse.is_finite() && r.seconds > 0.0)
                .map(|r| Circle::new((r.seconds, r.relmse), 3, colour.filled())),
        )?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
