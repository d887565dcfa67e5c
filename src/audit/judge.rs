//! From the pairs' clocks to the audit's verdicts: the closure of every triple ([`super::closure`]),
//! the source — or the pair — out of line, and the clock domains ([`super::domains`]). On plain data
//! (names, spans, a pair clock per pair), so that an audit read back from its JSON can be judged again
//! after one of its clocks is replaced (`rejudge`): what a curator does who knows better for one
//! source, and what the tests do to check that a source given a wrong clock is named.

use super::closure::{self, Culprit};
use super::domains;
use super::report::{Clock, Closure, Domain, OutOfLine, OutOfLineReason};
use crate::diag::{Warning, WarningCode};
use crate::report::json::TimeOffsetStatus;

/// The verdicts.
#[derive(Debug, Clone)]
pub struct Judged {
    pub closure: Vec<Closure>,
    pub domains: Vec<Domain>,
    /// Each source's domain name, in the sources' order.
    pub domain_of: Vec<String>,
    /// Sources out of line by closure.
    pub out_of_line: Vec<OutOfLine>,
    /// `clock_closure_failed`, when a triple does not close.
    pub warning: Option<Warning>,
}

type PairFn<'a> = dyn Fn(usize, usize) -> Option<Clock> + 'a;

/// Judges `names` (the reference first) whose spans (absolute seconds, own clocks) are `spans`, from
/// `pair(a, b)` (a < b: B's stamps onto A's clock).
pub fn judge(
    names: &[String],
    spans: &[(f64, f64)],
    pair: &PairFn<'_>,
    reference_span: (f64, f64),
) -> Judged {
    let pair = |a: usize, b: usize| pair(a.min(b), a.max(b));
    let (closures, triples) = closures(names, spans, &pair);
    let (domains, domain_of) = domains(names, &pair, reference_span);
    let (out_of_line, warning) = verdict(names, &closures, &triples);
    Judged {
        closure: closures,
        domains,
        domain_of,
        out_of_line,
        warning,
    }
}

/// The closure of every triple whose three pairs were measured with a usable offset, and each
/// triple's indices with whether it closes.
fn closures(
    names: &[String],
    spans: &[(f64, f64)],
    pair: &PairFn<'_>,
) -> (Vec<Closure>, Vec<([usize; 3], bool)>) {
    let n = names.len();
    let usable =
        |c: &Clock| c.status == TimeOffsetStatus::Ok || c.status == TimeOffsetStatus::Given;
    let mut closures = Vec::new();
    let mut triples = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                let (Some(ab), Some(bc), Some(ac)) = (pair(a, b), pair(b, c), pair(a, c)) else {
                    continue;
                };
                if !(usable(&ab) && usable(&bc) && usable(&ac)) {
                    continue;
                }
                let span = (
                    [a, b, c]
                        .iter()
                        .map(|&i| spans[i].0)
                        .fold(f64::NEG_INFINITY, f64::max),
                    [a, b, c]
                        .iter()
                        .map(|&i| spans[i].1)
                        .fold(f64::INFINITY, f64::min),
                );
                let Some(stat) = closure::closure(&ab, &bc, &ac, span) else {
                    continue;
                };
                triples.push(([a, b, c], stat.consistent));
                closures.push(Closure {
                    sources: [a, b, c].map(|i| names[i].clone()),
                    residual_s: stat.residual_s,
                    sigma_s: stat.sigma_s,
                    chi2: stat.chi2,
                    dof: stat.dof,
                    p_value: stat.p_value,
                    consistent: stat.consistent,
                });
            }
        }
    }
    (closures, triples)
}

/// The clock domains (the reference's first) and each source's domain name.
fn domains(
    names: &[String],
    pair: &PairFn<'_>,
    reference_span: (f64, f64),
) -> (Vec<Domain>, Vec<String>) {
    let n = names.len();
    let to_reference: Vec<Option<Clock>> = (0..n)
        .map(|i| if i == 0 { None } else { pair(0, i) })
        .collect();
    let sigmas: Vec<Option<f64>> = (0..n)
        .map(|i| match i {
            0 => Some(0.0),
            _ => to_reference[i].as_ref().and_then(|c| c.sigma_s),
        })
        .collect();
    let groups = domains::group(n, &sigmas, pair);
    let mut domain_of = vec![String::new(); n];
    let mut domain_list = Vec::new();
    for (k, g) in groups.iter().enumerate() {
        let name = names[g[0]].clone();
        for &i in g {
            domain_of[i] = name.clone();
        }
        let reference = Clock::reference(reference_span.0, reference_span.1);
        // The reference's domain is on its clock; another moves by its most precise member's.
        let clock = if k == 0 {
            reference
        } else {
            g.iter()
                .filter_map(|&i| to_reference[i].clone())
                .filter(|c| c.status == TimeOffsetStatus::Ok)
                .min_by(|a, b| {
                    a.sigma_s
                        .unwrap_or(f64::INFINITY)
                        .total_cmp(&b.sigma_s.unwrap_or(f64::INFINITY))
                })
                .or_else(|| to_reference[g[0]].clone())
                .unwrap_or(reference)
        };
        domain_list.push(Domain {
            name,
            sources: g.iter().map(|&i| names[i].clone()).collect(),
            reference: k == 0,
            clock,
        });
    }
    (domain_list, domain_of)
}

/// Who the failing triples single out (a source, or the two of one pair), and the warning.
fn verdict(
    names: &[String],
    closures: &[Closure],
    triples: &[([usize; 3], bool)],
) -> (Vec<OutOfLine>, Option<Warning>) {
    let failed: Vec<&Closure> = closures.iter().filter(|c| !c.consistent).collect();
    let Some(worst) = failed.iter().max_by(|a, b| a.chi2.total_cmp(&b.chi2)) else {
        return (Vec::new(), None);
    };
    let counts = format!(
        "{} of {} triples fail to close; worst: {} closes at {:+.1} ± {:.1} ms",
        failed.len(),
        closures.len(),
        worst.sources.join(", "),
        worst.residual_s * 1e3,
        worst.sigma_s * 1e3
    );
    let line = |name: &String, reason, detail: String| OutOfLine {
        source: name.clone(),
        reason,
        detail,
    };
    let mut out_of_line = Vec::new();
    let message = match closure::out_of_line(names.len(), triples) {
        Some(Culprit::Source(i)) => {
            let name = &names[i];
            out_of_line.push(line(
                name,
                OutOfLineReason::Closure,
                format!(
                    "{name}: every triple holding it fails to close, every other closes ({counts})"
                ),
            ));
            format!(
                "{name}: its clock offsets do not add up with the others' ({counts}); check its clock and its lever arm"
            )
        }
        Some(Culprit::Pair(i, j)) => {
            let (a, b) = (&names[i], &names[j]);
            for name in [a, b] {
                out_of_line.push(line(
                    name,
                    OutOfLineReason::PairClosure,
                    format!("{a}–{b}: their pair's offset disagrees with every chain through a third source ({counts})"),
                ));
            }
            format!(
                "{a}–{b}: the offset measured between them disagrees with every chain through a third source ({counts}); trust the chains"
            )
        }
        Some(Culprit::Unclear(c)) if !c.is_empty() => format!(
            "{counts}; the failures do not single out one source (every failing triple holds {})",
            c.iter()
                .map(|&i| names[i].as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        _ => format!("{counts}; the failures do not single out one source"),
    };
    (
        out_of_line,
        Some(Warning::new(WarningCode::ClockClosureFailed, message)),
    )
}

/// Judges an audit again from its pairs as they stand (after a clock was replaced): its closure,
/// domains, each source's domain, and the closure's entries of `out_of_line` and `warnings`.
#[cfg(test)]
pub fn rejudge(report: &mut super::report::AuditReport) {
    let names: Vec<String> = report.sources.iter().map(|s| s.name.clone()).collect();
    let spans: Vec<(f64, f64)> = report
        .sources
        .iter()
        .map(|s| (s.coverage.t_start, s.coverage.t_end))
        .collect();
    let index = |n: &str| names.iter().position(|x| x == n);
    let pairs = report.pairs.clone();
    let pair = |a: usize, b: usize| -> Option<Clock> {
        pairs
            .iter()
            .find(|p| index(&p.a) == Some(a) && index(&p.b) == Some(b))
            .map(|p| p.clock.clone())
    };
    let reference_span = spans.first().copied().unwrap_or((0.0, 0.0));
    let j = judge(&names, &spans, &pair, reference_span);
    report.closure = j.closure;
    report.domains = j.domains;
    for (s, d) in report.sources.iter_mut().zip(&j.domain_of) {
        s.domain = d.clone();
    }
    report.out_of_line.retain(|o| {
        !matches!(
            o.reason,
            OutOfLineReason::Closure | OutOfLineReason::PairClosure
        )
    });
    report.out_of_line.extend(j.out_of_line);
    report
        .warnings
        .retain(|w| w.code != WarningCode::ClockClosureFailed);
    report.warnings.extend(j.warning);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audit::report::AuditReport;

    /// On the simulator's multi-clock missions whose audit closes as measured, each source given a
    /// wrong clock (its pair offsets moved by 40–100 ms, each by a different amount) is the one the
    /// closure names; untouched, [`rejudge`] judges as the audit did.
    #[test]
    fn a_source_given_a_wrong_clock_is_named_by_the_closure() {
        let dir = tempfile::tempdir().unwrap();
        let run = |args: &[String]| {
            let code = crate::cli::main_with_args(
                std::iter::once("trajdrift".to_string())
                    .chain(args.iter().cloned())
                    .map(Into::into)
                    .collect(),
            );
            assert!(matches!(code, 0 | 3), "{args:?}: exit {code}");
        };
        let mut judged = 0;
        for seed in 1..=5 {
            let mission = dir.path().join(format!("seed{seed}"));
            let json = dir.path().join(format!("w{seed}.json"));
            let (m, j) = (mission.display().to_string(), json.display().to_string());
            run(&[
                "simulate",
                &m,
                "--grandtour",
                "--multi-clock",
                "--seed",
                &seed.to_string(),
                "--duration",
                "1200",
            ]
            .map(String::from));
            run(&["audit", &m, "--quiet", "--json", &j].map(String::from));
            let report: AuditReport =
                serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
            if report.closure.iter().any(|c| !c.consistent) {
                eprintln!("seed {seed}: the audit does not close as measured; skipped");
                continue;
            }
            for wrong in report.sources.iter().skip(1).map(|s| s.name.clone()) {
                let mut r = report.clone();
                let mut k = 0.0;
                for p in r.pairs.iter_mut().filter(|p| p.a == wrong || p.b == wrong) {
                    k += 1.0;
                    let e = 0.02 + 0.02 * k;
                    p.clock.offset_s += e;
                    for s in &mut p.clock.segments {
                        s.offset_s += e;
                    }
                }
                rejudge(&mut r);
                let named: Vec<_> = r
                    .out_of_line
                    .iter()
                    .filter(|o| o.reason == OutOfLineReason::Closure)
                    .map(|o| o.source.as_str())
                    .collect();
                assert_eq!(named, [wrong.as_str()], "seed {seed}: {:?}", r.closure);
                judged += 1;
            }
            // Untouched, it judges the same (the spans read back from the JSON's coverage, on the reference
            // clock, move the pieces' middles a little: a drifting pair's residual by tens of µs).
            let mut same = report.clone();
            rejudge(&mut same);
            for (x, y) in same.closure.iter().zip(&report.closure) {
                assert_eq!((&x.sources, x.consistent), (&y.sources, y.consistent));
                assert!((x.residual_s - y.residual_s).abs() < 1e-4, "{x:?} {y:?}");
            }
            let groups = |r: &AuditReport| -> Vec<Vec<String>> {
                r.domains.iter().map(|d| d.sources.clone()).collect()
            };
            assert_eq!(groups(&same), groups(&report));
        }
        assert!(judged > 0, "no seed closed as measured");
    }
}
