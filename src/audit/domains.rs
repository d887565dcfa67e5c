//! Clock domains: sources on the same clock.
//!
//! Two sources share a clock when their pair's clock model is constant (no relative drift or step)
//! and its offset is within 3σ of zero (σ the evaluation's own). A pair never measured (no overlap, a
//! failed search) is judged through the reference, Δt_AB = Δt_RB − Δt_RA with σ² = σ_RA² + σ_RB², when
//! both clocks against the reference are constant. Domains are grown greedily, the reference first,
//! then the others from the most precise clock to the least: a source joins the first domain it
//! shares a clock with **every** member of (complete linkage, so a chain of near-misses never merges
//! two clocks 5σ apart), or starts a new one.
//!
//! A domain is named after its first member (the reference's domain after the reference). Its clock
//! against the reference is the reference's own (0, constant) for the reference's domain, else its
//! most precise member's: what `restamp` maps the domain by.

use super::report::Clock;
use crate::report::json::TimeOffsetStatus;

/// Offsets within this many σ of zero are the same clock.
pub const SAME_CLOCK_SIGMAS: f64 = 3.0;

/// Whether a clock between two sources says they are the same clock.
pub fn same_clock(c: &Clock) -> bool {
    c.status == TimeOffsetStatus::Ok
        && c.is_constant()
        && c.sigma_s
            .is_some_and(|s| s.is_finite() && c.offset_s.abs() <= SAME_CLOCK_SIGMAS * s)
}

/// The pair clock of (a, b), direct, or through the reference (index 0) when not measured.
fn relation(a: usize, b: usize, pair: &dyn Fn(usize, usize) -> Option<Clock>) -> Option<Clock> {
    let (a, b) = (a.min(b), a.max(b));
    if let Some(c) = pair(a, b) {
        return Some(c);
    }
    let (ra, rb) = (pair(0, a)?, pair(0, b)?);
    if !(ra.is_constant() && rb.is_constant())
        || ra.status != TimeOffsetStatus::Ok
        || rb.status != TimeOffsetStatus::Ok
    {
        return None;
    }
    let sigma = ra.sigma_s?.hypot(rb.sigma_s?);
    Some(Clock {
        offset_s: rb.offset_s - ra.offset_s,
        sigma_s: Some(sigma),
        ..rb
    })
}

/// Groups `n` sources (index 0 the reference) into domains, given each source's σ against the
/// reference (for the order) and the pair clocks (`pair(a, b)`, a < b). Returns the domains as lists
/// of indices, the reference's first.
pub fn group(
    n: usize,
    sigma_to_reference: &[Option<f64>],
    pair: &dyn Fn(usize, usize) -> Option<Clock>,
) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (1..n).collect();
    order.sort_by(|&a, &b| {
        let s = |i: usize| sigma_to_reference[i].unwrap_or(f64::INFINITY);
        s(a).total_cmp(&s(b)).then(a.cmp(&b))
    });
    let mut domains: Vec<Vec<usize>> = vec![vec![0]];
    for i in order {
        let home = domains.iter().position(|d| {
            d.iter()
                .all(|&m| relation(m, i, pair).is_some_and(|c| same_clock(&c)))
        });
        match home {
            Some(k) => domains[k].push(i),
            None => domains.push(vec![i]),
        }
    }
    domains
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::clock_model::OffsetModel;

    fn c(offset_s: f64, sigma_s: f64, model: OffsetModel) -> Clock {
        Clock {
            model,
            method: crate::audit::report::ClockMethod::Speed,
            ..crate::audit::report::examples::constant(offset_s, sigma_s)
        }
    }

    #[test]
    fn shared_offset_drifting_and_unmeasured_pairs() {
        use OffsetModel::*;
        // 0 reference; 1 on its clock; 2 and 3 one clock 0.2 s late; 4 drifting.
        let table = |a: usize, b: usize| -> Option<Clock> {
            Some(match (a, b) {
                (0, 1) => c(0.001, 0.002, Constant),
                (0, 2) => c(0.2, 0.002, Constant),
                (0, 3) => c(0.201, 0.003, Constant),
                (0, 4) => c(0.1, 0.002, Linear),
                (1, 2) => c(0.199, 0.002, Constant),
                (1, 3) => c(0.2, 0.003, Constant),
                (1, 4) => c(0.1, 0.002, Linear),
                (2, 3) => return None, // never measured: through the reference, 0.001 ± 0.004
                (2, 4) | (3, 4) => c(-0.1, 0.002, Linear),
                _ => return None,
            })
        };
        let sigma = [
            Some(0.0),
            Some(0.002),
            Some(0.002),
            Some(0.003),
            Some(0.002),
        ];
        let d = group(5, &sigma, &table);
        assert_eq!(d, vec![vec![0, 1], vec![2, 3], vec![4]]);
    }

    #[test]
    fn complete_linkage_keeps_a_chain_of_near_misses_apart() {
        // 1 is 2.5σ from 0, 2 is 2.5σ from 1 but 5σ from 0.
        let table = |a: usize, b: usize| -> Option<Clock> {
            Some(match (a, b) {
                (0, 1) => c(0.005, 0.002, OffsetModel::Constant),
                (0, 2) => c(0.010, 0.002, OffsetModel::Constant),
                (1, 2) => c(0.005, 0.002, OffsetModel::Constant),
                _ => return None,
            })
        };
        let d = group(3, &[Some(0.0), Some(0.002), Some(0.002)], &table);
        assert_eq!(d, vec![vec![0, 1], vec![2]]);
    }
}
