//! evo_res's statistics table, character for character: evo prints
//! `df.loc["stats"].T.to_string(line_width=80)` of a pandas frame of Python objects, so each value is
//! `f"{x: .6f}"` with trailing zeros trimmed (`0.000350` → `0.00035`, keeping one decimal), each column
//! right-justified to its widest cell, the index left-justified, and the columns wrapped into blocks
//! no wider than 80 characters with ` \` at the end of every block but the last (pandas'
//! `StringFormatter._join_multiline` and `_binify`, pandas 2 and 3).

/// A value as pandas prints an object cell holding a float (precision 6).
pub fn pandas_float(v: Option<f64>) -> String {
    let Some(v) = v else {
        return "NaN".into();
    };
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { " inf" } else { "-inf" }.into();
    }
    let s = format!("{:.6}", v);
    let s = if v >= 0.0 && !s.starts_with('-') {
        format!(" {s}")
    } else {
        s
    };
    let t = s.trim_end_matches('0');
    if t.ends_with('.') {
        format!("{t}0")
    } else {
        t.to_string()
    }
}

/// The table of `rows` × `columns` as pandas' `DataFrame.to_string(line_width=80)` prints it.
pub fn pandas_table(rows: &[String], columns: &[String], cells: &[Vec<Option<f64>>]) -> String {
    let idx_w = rows.iter().map(|r| r.chars().count()).max().unwrap_or(0);
    let mut idx: Vec<String> = vec![String::new()];
    idx.extend(rows.iter().cloned());
    // Each data column: header and values, right-justified to the widest.
    let strcols: Vec<Vec<String>> = columns
        .iter()
        .enumerate()
        .map(|(c, h)| {
            let vals: Vec<String> = cells
                .iter()
                .map(|r| pandas_float(r.get(c).copied().flatten()))
                .collect();
            let w = vals
                .iter()
                .map(|v| v.chars().count())
                .chain([h.chars().count()])
                .max()
                .unwrap_or(0);
            std::iter::once(h)
                .chain(vals.iter())
                .map(|s| format!("{s:>w$}"))
                .collect()
        })
        .collect();
    let widths: Vec<usize> = strcols
        .iter()
        .map(|c| c.iter().map(|s| s.chars().count()).max().unwrap_or(0))
        .collect();
    let bins = binify(&widths, 80 - (idx_w + 1));
    let nrows = idx.len();
    let mut blocks = Vec::new();
    let mut start = 0;
    for (b, &end) in bins.iter().enumerate() {
        let mut lists: Vec<Vec<String>> = vec![idx.clone()];
        lists.extend(strcols[start..end].iter().cloned());
        if bins.len() > 1 {
            if b < bins.len() - 1 {
                let mut cont = vec![" \\".to_string()];
                cont.extend(std::iter::repeat_n("  ".to_string(), nrows - 1));
                lists.push(cont);
            } else {
                lists.push(vec![" ".to_string(); nrows]);
            }
        }
        blocks.push(adjoin(&lists));
        start = end;
    }
    blocks.join("\n\n")
}

/// pandas' `_binify`: where the columns wrap.
fn binify(widths: &[usize], line_width: usize) -> Vec<usize> {
    let mut bins = Vec::new();
    let mut curr = 0usize;
    let last = widths.len().saturating_sub(1);
    for (i, &w) in widths.iter().enumerate() {
        let wa = w + 1;
        curr += wa;
        let wrap = if i == last {
            curr + 1 > line_width && i > 0
        } else {
            curr + 2 > line_width && i > 0
        };
        if wrap {
            bins.push(i);
            curr = wa;
        }
    }
    bins.push(widths.len());
    bins
}

/// pandas' `adjoin(1, *lists)`: every list but the last left-justified to its width + 1.
fn adjoin(lists: &[Vec<String>]) -> String {
    let n = lists.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = lists
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let w = l.iter().map(|s| s.chars().count()).max().unwrap_or(0);
            if k + 1 < lists.len() {
                w + 1
            } else {
                w
            }
        })
        .collect();
    (0..n)
        .map(|r| {
            lists
                .iter()
                .zip(&widths)
                .map(|(l, &w)| format!("{:<w$}", l.get(r).map_or("", String::as_str)))
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pandas_table_aligns_like_pandas() {
        let t = pandas_table(
            &["a.txt".into(), "b.txt".into()],
            &["rmse".into(), "min".into()],
            &[
                vec![Some(0.008119), Some(0.00035)],
                vec![Some(1.30345), Some(2.0)],
            ],
        );
        assert_eq!(
            t,
            "           rmse      min\na.txt  0.008119  0.00035\nb.txt   1.30345      2.0"
        );
    }

    /// evo_res 1.38.1 (pandas 3.1) on two of evo's own zips, as printed.
    #[test]
    fn wraps_like_pandas() {
        let t = pandas_table(
            &["ape.zip".into(), "kape.zip".into()],
            &["rmse", "mean", "median", "std", "min", "max", "sse"].map(String::from),
            &[
                vec![
                    Some(0.008118977562045396),
                    Some(0.007491776870216619),
                    Some(0.0074146298293173854),
                    Some(0.0031290695070394156),
                    Some(0.00034963619840638655),
                    Some(0.024299593694385224),
                    Some(0.14330528992361463),
                ],
                vec![
                    Some(1.30345),
                    Some(1.156997),
                    Some(1.065625),
                    Some(0.600282),
                    Some(0.069313),
                    Some(3.587949),
                    Some(7715.07344),
                ],
            ],
        );
        let want = [
            "              rmse      mean    median       std       min       max  \\",
            "ape.zip   0.008119  0.007492  0.007415  0.003129   0.00035    0.0243   ",
            "kape.zip   1.30345  1.156997  1.065625  0.600282  0.069313  3.587949   ",
            "",
            "                 sse  ",
            "ape.zip     0.143305  ",
            "kape.zip  7715.07344  ",
        ]
        .join("\n");
        assert_eq!(t, want);
    }
}
