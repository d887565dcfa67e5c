//! `trajdrift res`: evo_res over result files written by evo or by trajdrift. Loads them, labels
//! them (`est_name`'s file name, or the result file's path with `--use_filenames`), merges them
//! (`--merge`, evo's `merge_results`), prints evo_res's title and table, writes the table
//! (`--save_table`) and the figures (raw, stats, histogram, box_plot, violin_histogram), and, beyond
//! evo_res, the statistics over repeated runs and a paired comparison ([`super::runs`]).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::plot::evo::{Distributions, ErrorSeries, EvoFigure, Histograms, StatsBars};
use crate::report::evo_zip::{py_float, EvoResult};

use super::runs::{compare, estimator_of, mean_interval, Comparison, MissionPair, Verdict};
use super::table::pandas_table;

/// One loaded result file.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub path: PathBuf,
    pub label: String,
    pub result: EvoResult,
}

/// Reads every file; labels as evo_res does.
pub fn load(paths: &[PathBuf], use_filenames: bool) -> Result<Vec<Loaded>> {
    paths
        .iter()
        .map(|p| {
            let result = EvoResult::read(p)?;
            let label = if use_filenames {
                p.display().to_string()
            } else {
                label_of(&result)
            };
            Ok(Loaded {
                path: p.clone(),
                label,
                result,
            })
        })
        .collect()
}

/// `os.path.basename(info["est_name"])`, or evo's `unnamed_result`.
fn label_of(r: &EvoResult) -> String {
    match r.info_str("est_name") {
        Some(n) => n.rsplit('/').next().unwrap_or(n).to_string(),
        None => "unnamed_result".into(),
    }
}

/// evo's `merge_results`: statistics averaged; arrays averaged element-wise when every result's
/// arrays have the same sizes, else appended; the first result's info.
pub fn merge(results: &[Loaded]) -> Result<Loaded> {
    let first = results
        .first()
        .ok_or_else(|| Error::InvalidArgument("no result file to merge".into()))?;
    let keys = |r: &EvoResult| {
        (
            r.stats.iter().map(|s| s.0.clone()).collect::<Vec<_>>(),
            r.arrays.iter().map(|a| a.0.clone()).collect::<Vec<_>>(),
        )
    };
    let mut sorted_first = keys(&first.result);
    sorted_first.0.sort();
    sorted_first.1.sort();
    for r in &results[1..] {
        let mut k = keys(&r.result);
        k.0.sort();
        k.1.sort();
        if k != sorted_first {
            return Err(Error::InvalidArgument(format!(
                "--merge: {} and {} have different statistics or arrays; can't merge results with non-matching keys",
                first.path.display(),
                r.path.display()
            )));
        }
    }
    let sizes = |r: &EvoResult| r.arrays.iter().map(|a| a.1.data.len()).collect::<Vec<_>>();
    let average = results
        .iter()
        .all(|r| sizes(&r.result) == sizes(&first.result));
    let n = results.len() as f64;
    let mut merged = first.result.clone();
    for (k, v) in merged.stats.iter_mut() {
        let sum: f64 = results.iter().filter_map(|r| r.result.stat(k)).sum();
        *v = sum / n;
    }
    for (name, a) in merged.arrays.iter_mut() {
        if average {
            for (i, x) in a.data.iter_mut().enumerate() {
                let sum: f64 = results
                    .iter()
                    .filter_map(|r| r.result.array(name).map(|b| b.data[i]))
                    .sum();
                *x = sum / n;
            }
        } else {
            a.data = results
                .iter()
                .filter_map(|r| r.result.array(name))
                .flat_map(|b| b.data.iter().copied())
                .collect();
            a.shape = vec![a.data.len()];
        }
    }
    Ok(Loaded {
        path: first.path.clone(),
        label: label_of(&merged),
        result: merged,
    })
}

/// The statistics' names in table order: the first result's, then any others.
pub fn stat_names(results: &[Loaded]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in results {
        for (k, _) in &r.result.stats {
            if !names.contains(k) {
                names.push(k.clone());
            }
        }
    }
    names
}

/// One-line error when two results share a label (evo_res refuses them too).
pub fn check_unique(results: &[Loaded]) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    let dups: Vec<&str> = results
        .iter()
        .filter(|r| !seen.insert(r.label.as_str()))
        .map(|r| r.label.as_str())
        .collect();
    if dups.is_empty() {
        return Ok(());
    }
    Err(Error::InvalidArgument(format!(
        "labels (est_name) must be unique, duplicates: {}; use --use_filenames to label the results by their file names",
        dups.join(", ")
    )))
}

/// Results whose title differs from the first one's: (file, its title).
pub fn title_conflicts(results: &[Loaded]) -> Vec<(PathBuf, String)> {
    let first = results.first().and_then(|r| r.result.info_str("title"));
    results
        .iter()
        .filter(|r| r.result.info_str("title") != first)
        .map(|r| {
            (
                r.path.clone(),
                r.result.info_str("title").unwrap_or("").to_string(),
            )
        })
        .collect()
}

/// What evo_res prints: the first title (unless `ignore_title`) and the table.
pub fn render(results: &[Loaded], ignore_title: bool) -> String {
    let names = stat_names(results);
    let rows: Vec<String> = results.iter().map(|r| r.label.clone()).collect();
    let cells: Vec<Vec<Option<f64>>> = results
        .iter()
        .map(|r| names.iter().map(|n| r.result.stat(n)).collect())
        .collect();
    let mut s = String::new();
    if !ignore_title {
        let title = results
            .first()
            .and_then(|r| r.result.info_str("title"))
            .unwrap_or("");
        s += &format!("\n{title}\n\n\n");
    }
    s += &pandas_table(&rows, &names, &cells);
    s += "\n\n";
    s
}

/// The table file's format, by the extension of `--save_table`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableFormat {
    Csv,
    Json,
    Markdown,
}

impl TableFormat {
    /// `.json` → JSON, `.md`/`.markdown` → Markdown, anything else CSV (evo's default).
    pub fn of(path: &Path) -> TableFormat {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("json") => TableFormat::Json,
            Some("md" | "markdown") => TableFormat::Markdown,
            _ => TableFormat::Csv,
        }
    }
}

fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The statistics table as evo_res's `--save_table` writes it (CSV: pandas' `to_csv` of the
/// transposed stats, floats in Python's repr; JSON: pandas' `to_json` layout
/// `{"rmse": {"label": value}}` at full precision; Markdown: a pipe table at 6 decimals).
pub fn table_file(results: &[Loaded], format: TableFormat) -> String {
    let names = stat_names(results);
    match format {
        TableFormat::Csv => {
            let mut s = String::new();
            s += &format!(
                ",{}\n",
                names
                    .iter()
                    .map(|n| csv_cell(n))
                    .collect::<Vec<_>>()
                    .join(",")
            );
            for r in results {
                let vals: Vec<String> = names
                    .iter()
                    .map(|n| r.result.stat(n).map(py_float).unwrap_or_default())
                    .collect();
                s += &format!("{},{}\n", csv_cell(&r.label), vals.join(","));
            }
            s
        }
        TableFormat::Json => {
            let mut root = serde_json::Map::new();
            for n in &names {
                let mut col = serde_json::Map::new();
                for r in results {
                    col.insert(
                        r.label.clone(),
                        r.result
                            .stat(n)
                            .and_then(serde_json::Number::from_f64)
                            .map_or(serde_json::Value::Null, serde_json::Value::Number),
                    );
                }
                root.insert(n.clone(), serde_json::Value::Object(col));
            }
            let mut s =
                serde_json::to_string_pretty(&serde_json::Value::Object(root)).unwrap_or_default();
            s.push('\n');
            s
        }
        TableFormat::Markdown => {
            let mut s = format!("| |{}|\n", names.join("|"));
            s += &format!("|---|{}|\n", vec!["---:"; names.len()].join("|"));
            for r in results {
                let vals: Vec<String> = names
                    .iter()
                    .map(|n| {
                        r.result
                            .stat(n)
                            .map_or(String::new(), |v| format!("{v:.6}"))
                    })
                    .collect();
                s += &format!("| {} |{}|\n", r.label.replace('|', "\\|"), vals.join("|"));
            }
            s
        }
    }
}

/// The x values of a result's raw figure: its timestamps (or seconds from start with
/// `use_rel_time`), else the index; and the axis label.
fn raw_x(r: &EvoResult, use_rel_time: bool) -> (Vec<f64>, &'static str) {
    let n = r.array("error_array").map_or(0, |a| a.data.len());
    let pick = if use_rel_time {
        ["seconds_from_start", "sec_from_start"].as_slice()
    } else {
        ["timestamps", "seconds_from_start", "sec_from_start"].as_slice()
    };
    for k in pick {
        if let Some(a) = r.array(k).filter(|a| a.data.len() == n) {
            return (a.data.clone(), "t (s)");
        }
    }
    ((0..n).map(|i| i as f64).collect(), "index")
}

/// evo_res's figures: raw, stats, histogram, box_plot, violin_histogram. Titles and axis labels
/// come from the first result; the figures themselves from `raw_figure` and `stats_figure` and
/// the same per-result values for the three distribution figures.
pub fn figures(
    results: &[Loaded],
    ignore_title: bool,
    use_rel_time: bool,
    markers: bool,
) -> Vec<(String, EvoFigure)> {
    let first = results.first().map(|r| &r.result);
    let title = if ignore_title {
        String::new()
    } else {
        first
            .and_then(|r| r.info_str("title"))
            .unwrap_or("")
            .replace('\n', " ")
    };
    let value_label = first
        .and_then(|r| r.info_str("label"))
        .unwrap_or("value")
        .to_string();
    let by_result: Vec<(String, Vec<f64>)> = results
        .iter()
        .map(|r| (r.label.clone(), error_values(r)))
        .collect();
    let distributions = |violin: bool| Distributions {
        title: title.clone(),
        value_label: value_label.clone(),
        results: by_result.clone(),
        violin,
    };
    vec![
        (
            "raw".into(),
            raw_figure(results, &title, &value_label, use_rel_time, markers),
        ),
        ("stats".into(), stats_figure(results, &title, &value_label)),
        (
            "histogram".into(),
            EvoFigure::Histograms(Histograms {
                title: title.clone(),
                value_label: value_label.clone(),
                results: by_result.clone(),
            }),
        ),
        (
            "box_plot".into(),
            EvoFigure::Distributions(distributions(false)),
        ),
        (
            "violin_histogram".into(),
            EvoFigure::Distributions(distributions(true)),
        ),
    ]
}

/// A result's `error_array` (empty when it has none).
fn error_values(r: &Loaded) -> Vec<f64> {
    r.result
        .array("error_array")
        .map(|a| a.data.clone())
        .unwrap_or_default()
}

/// The raw figure: every result's values over its own x values ([`raw_x`]), the axis named after
/// the first result's.
fn raw_figure(
    results: &[Loaded],
    title: &str,
    value_label: &str,
    use_rel_time: bool,
    markers: bool,
) -> EvoFigure {
    let series: Vec<(String, Vec<(f64, f64)>)> = results
        .iter()
        .map(|r| {
            let (x, _) = raw_x(&r.result, use_rel_time);
            (
                r.label.clone(),
                x.into_iter().zip(error_values(r)).collect(),
            )
        })
        .collect();
    let x_label = results
        .first()
        .map_or("index", |r| raw_x(&r.result, use_rel_time).1);
    EvoFigure::Errors(ErrorSeries {
        title: title.to_string(),
        x_label: x_label.into(),
        y_label: value_label.to_string(),
        series,
        stats: Vec::new(),
        markers,
    })
}

/// The statistics figure: the plotted statistics (rmse, median, mean, std, min, max, in the table's
/// order) of every result as bars; a statistic a result lacks draws as 0.
fn stats_figure(results: &[Loaded], title: &str, value_label: &str) -> EvoFigure {
    let plotted = ["rmse", "median", "mean", "std", "min", "max"];
    let stats: Vec<String> = stat_names(results)
        .into_iter()
        .filter(|s| plotted.contains(&s.as_str()))
        .collect();
    EvoFigure::Stats(StatsBars {
        title: title.to_string(),
        value_label: value_label.to_string(),
        results: results
            .iter()
            .map(|r| {
                (
                    r.label.clone(),
                    stats
                        .iter()
                        .map(|s| r.result.stat(s).unwrap_or(0.0))
                        .collect(),
                )
            })
            .collect(),
        stats,
    })
}

/// The mission a result belongs to: its reference's name.
fn mission_of(r: &EvoResult) -> String {
    r.info_str("ref_name")
        .unwrap_or("(no reference name)")
        .to_string()
}

/// A short, still distinct name for each of `missions` (full reference names): the file name, or as
/// many trailing path components as it takes (`lever_arm/reference.tum`).
pub fn short_names(missions: &[String]) -> Vec<String> {
    let tail = |m: &str, k: usize| {
        let parts: Vec<&str> = m.split('/').filter(|p| !p.is_empty()).collect();
        parts[parts.len().saturating_sub(k)..].join("/")
    };
    let mut distinct = missions.to_vec();
    distinct.sort();
    distinct.dedup();
    for k in 1..=16 {
        let names: Vec<String> = missions.iter().map(|m| tail(m, k)).collect();
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        if unique.len() >= distinct.len() {
            return names;
        }
    }
    missions.to_vec()
}

/// `--runs`: per estimator (file name less its run number) and mission (reference), the mean ± 95 %
/// interval of each statistic over the runs.
pub fn runs_report(results: &[Loaded]) -> String {
    let names: Vec<String> = stat_names(results)
        .into_iter()
        .filter(|n| n != "sse")
        .collect();
    let mut groups: Vec<((String, String), Vec<&Loaded>)> = Vec::new();
    for r in results {
        let key = (estimator_of(&r.path), mission_of(&r.result));
        match groups.iter_mut().find(|g| g.0 == key) {
            Some(g) => g.1.push(r),
            None => groups.push((key, vec![r])),
        }
    }
    let mut s = String::from("mean ± 95 % interval over repeated runs (Student's t)\n");
    let header: Vec<String> = ["estimator", "mission", "runs"]
        .iter()
        .map(|h| h.to_string())
        .chain(names.iter().cloned())
        .collect();
    let mut rows = vec![header];
    let shorts = short_names(&groups.iter().map(|g| g.0 .1.clone()).collect::<Vec<_>>());
    for (((est, _), rs), mission) in groups.iter().zip(shorts) {
        let mut row = vec![est.clone(), mission, rs.len().to_string()];
        for n in &names {
            let v: Vec<f64> = rs.iter().filter_map(|r| r.result.stat(n)).collect();
            row.push(match mean_interval(&v) {
                Some(i) => format!("{:.6} ± {:.6}", i.mean, i.half_width),
                None if v.len() == 1 => format!("{:.6} (1 run)", v[0]),
                None => "–".into(),
            });
        }
        rows.push(row);
    }
    s += &aligned(&rows);
    s
}

/// `--compare A B`: B against A on the missions both ran, on statistic `stat`: the estimators are
/// checked, the values paired by mission (`mission_pairs`), compared ([`compare`]) and reported
/// (`comparison_text`).
pub fn compare_report(
    results: &[Loaded],
    a: &str,
    b: &str,
    stat: &str,
) -> Result<(String, Verdict)> {
    let known: Vec<String> = {
        let mut k: Vec<String> = results.iter().map(|r| estimator_of(&r.path)).collect();
        k.dedup();
        k
    };
    for name in [a, b] {
        if !known.iter().any(|k| k == name) {
            return Err(Error::InvalidArgument(format!(
                "--compare {name}: no result file of that estimator; estimators (file names less the run number): {}",
                known.join(", ")
            )));
        }
    }
    let missions = mission_pairs(results, a, b, stat)?;
    let c = compare(&missions);
    Ok((comparison_text(&missions, &c, a, b, stat), c.verdict))
}

/// The values of `stat` of estimators `a` and `b`, by mission in the order missions first appear;
/// a result of either without `stat` is an error.
fn mission_pairs(results: &[Loaded], a: &str, b: &str, stat: &str) -> Result<Vec<MissionPair>> {
    let mut missions: Vec<MissionPair> = Vec::new();
    for r in results {
        let est = estimator_of(&r.path);
        let side = if est == a {
            0
        } else if est == b {
            1
        } else {
            continue;
        };
        let Some(v) = r.result.stat(stat) else {
            return Err(Error::InvalidArgument(format!(
                "--compare_stat {stat}: {} has no such statistic",
                r.path.display()
            )));
        };
        let m = mission_of(&r.result);
        let entry = match missions.iter_mut().position(|x| x.mission == m) {
            Some(i) => &mut missions[i],
            None => {
                missions.push(MissionPair {
                    mission: m,
                    a: Vec::new(),
                    b: Vec::new(),
                });
                missions.last_mut().expect("pushed")
            }
        };
        if side == 0 {
            entry.a.push(v);
        } else {
            entry.b.push(v);
        }
    }
    Ok(missions)
}

/// The comparison as printed: a row per mission both ran, the relative difference with its
/// interval, and the verdict in words.
fn comparison_text(
    missions: &[MissionPair],
    c: &Comparison,
    a: &str,
    b: &str,
    stat: &str,
) -> String {
    let mut rows = vec![vec![
        "mission".to_string(),
        format!("{a} runs"),
        format!("{a} {stat}"),
        format!("{b} runs"),
        format!("{b} {stat}"),
        format!("({b} − {a})/{a}"),
    ]];
    let shorts = short_names(&c.missions.iter().map(|m| m.0.clone()).collect::<Vec<_>>());
    for ((m, pair), short) in c
        .missions
        .iter()
        .zip(
            missions
                .iter()
                .filter(|m| !m.a.is_empty() && !m.b.is_empty()),
        )
        .zip(shorts)
    {
        rows.push(vec![
            short,
            pair.a.len().to_string(),
            format!("{:.6}", m.1),
            pair.b.len().to_string(),
            format!("{:.6}", m.2),
            match m.4 {
                Some(h) => format!("{:+.2} % ± {:.2} %", 100.0 * m.3, 100.0 * h),
                None => format!("{:+.2} %", 100.0 * m.3),
            },
        ]);
    }
    let mut s = format!("paired comparison of {stat}: {b} against {a}\n");
    s += &aligned(&rows);
    s += &format!(
        "\n{b} − {a}: {:+.2} % ± {:.2} % of {a}'s {stat} (95 % interval, {})\n",
        100.0 * c.relative,
        100.0 * c.half_width,
        c.method
    );
    s += &match c.verdict {
        Verdict::BBetter => {
            format!("better: {b} (lower {stat}; the difference exceeds the run-to-run scatter)\n")
        }
        Verdict::BWorse => {
            format!("better: {a} (lower {stat}; the difference exceeds the run-to-run scatter)\n")
        }
        Verdict::NoDifference => {
            "no difference: within the run-to-run scatter (the 95 % interval contains 0)\n"
                .to_string()
        }
        Verdict::Undecided => {
            "undecided: give two runs or more of each estimator, or two missions or more\n"
                .to_string()
        }
    };
    s
}

/// Rows of cells as left-aligned columns.
fn aligned(rows: &[Vec<String>]) -> String {
    let cols = rows.iter().map(Vec::len).max().unwrap_or(0);
    let w: Vec<usize> = (0..cols)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    rows.iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .map(|(c, s)| format!("{s:<width$}", width = w[c]))
                .collect::<Vec<_>>()
                .join("  ")
                .trim_end()
                .to_string()
                + "\n"
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_names_take_as_many_components_as_they_need() {
        let m = [
            "/d/a/reference.tum".to_string(),
            "/d/b/reference.tum".to_string(),
        ];
        assert_eq!(short_names(&m), ["a/reference.tum", "b/reference.tum"]);
        assert_eq!(short_names(&m[..1]), ["reference.tum"]);
    }
}
