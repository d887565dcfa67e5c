//! One estimate's clock offset in the evaluation: given (`--time-offset`), or searched — every
//! signal method under `auto` (refined by the pose fit where the estimate has orientations,
//! rescued from a weak answer where the fit can start elsewhere) or the one method named — with its
//! clock model over time, and the report's rows, reason and warnings for it.

use super::config::EvalConfig;
use super::inputs::Loaded;
use crate::align::auto_offset::auto_time_offset_of;
use crate::align::clock_model::{clock_model_of, OffsetModel};
use crate::align::time_offset::{
    estimate_time_offset_cached, OffsetEstimate, OffsetMethod, OffsetParams, OffsetStatus, Pair,
    SignalCache,
};
use crate::diag::{Warning, WarningCode};
use crate::error::{Error, Result};
use crate::report::json::{
    MethodStatus, OffsetMethodReport, OffsetProfilePoint, OffsetSegmentReport, OffsetSource,
    TimeOffsetReport, TimeOffsetStatus,
};

/// One signal method's row of the report's `methods`: its answer and confidence, or its error.
fn method_report(method: OffsetMethod, r: &Result<OffsetEstimate>) -> OffsetMethodReport {
    match r {
        Ok(o) => OffsetMethodReport {
            method,
            offset_s: Some(o.offset_s),
            correlation: Some(o.correlation),
            confidence: Some(o.confidence),
            status: o.status.into(),
            error: None,
            margin: Some(o.margin),
            defined_fraction: Some(o.defined_fraction),
        },
        Err(e) => OffsetMethodReport {
            method,
            offset_s: None,
            correlation: None,
            confidence: None,
            status: MethodStatus::Failed,
            error: Some(e.to_string()),
            margin: None,
            defined_fraction: None,
        },
    }
}

/// `--time-offset S`: applied as given, no search.
pub(super) fn given_offset(dt: f64) -> TimeOffsetReport {
    TimeOffsetReport {
        method: OffsetSource::Given,
        offset_s: dt,
        applied_s: dt,
        status: TimeOffsetStatus::Given,
        reason: Some("given with --time-offset".into()),
        model: Some(OffsetModel::Constant),
        ..Default::default()
    }
}

/// What the searches said, whatever their answer: each method's row, why the answer is the one
/// chosen, and the lever arm a disagreement implies.
struct Searched {
    methods: Vec<OffsetMethodReport>,
    reason: String,
    implied_lever: Option<f64>,
}

/// The searched time offset: `auto` runs every method (and refines the answer by the pose fit
/// when the estimate has orientations), a named method runs alone; over time, its clock model.
pub(super) fn searched_offset(
    config: &EvalConfig,
    (ref_t, ref_p): (&[f64], &[nalgebra::Vector3<f64>]),
    est_t: &[f64],
    est: &Loaded,
    t0_ns: i64,
) -> Result<(TimeOffsetReport, Vec<Warning>)> {
    // The methods' signals, computed once for the search, the `auto` re-run and the profile, and
    // dropped on return (before the metrics copy the trajectories).
    let cache = SignalCache::default();
    let pair = Pair::new((ref_t, ref_p), (est_t, &est.trajectory.positions), &cache);
    let params = config.offset_params();
    let method = config.params.offset_method();
    let search = OffsetSearch {
        config,
        params: &params,
        pair: &pair,
        est,
        t0_s: t0_ns as f64 * 1e-9,
        jumps: std::cell::OnceCell::new(),
    };
    let mut warnings = Vec::new();
    // `auto` runs every method; a named method runs alone (only what it needs is computed).
    if let (Some(start), true) = (config.start_offset_s, est.trajectory.orientations.is_some()) {
        let searched = Searched {
            methods: Vec::new(),
            reason: format!("started at {start:+.4} s, not searched"),
            implied_lever: None,
        };
        let o = OffsetEstimate {
            method: OffsetMethod::Speed,
            offset_s: start,
            correlation: f64::NAN,
            confidence: f64::NAN,
            status: OffsetStatus::Ok,
            overlap_fraction: 1.0,
            margin: f64::NAN,
            rival_offset_s: None,
            defined_fraction: 1.0,
            sigma_s: None,
        };
        return Ok(search.accepted_offset(&o, searched));
    }
    let auto = if method == OffsetMethod::Auto {
        Some(match auto_time_offset_of(&pair, &params) {
            Ok(a) => a,
            Err(e @ Error::NoOverlap { .. }) => return Err(clone_no_overlap(&e, &est.label)),
            Err(e) => return Err(relabel(e, &est.label)),
        })
    } else {
        None
    };
    let single: Vec<(OffsetMethod, Result<OffsetEstimate>)> = match auto {
        Some(_) => Vec::new(),
        None => vec![(
            method,
            estimate_time_offset_cached(method, &pair, &params, (&[], &[])),
        )],
    };
    let runs = auto.as_ref().map_or(&single, |a| &a.runs);
    let methods: Vec<OffsetMethodReport> = runs.iter().map(|(m, r)| method_report(*m, r)).collect();
    // The answer of the requested method (`auto`: the combined one) and why.
    let (chosen, searched) = match &auto {
        Some(auto) => {
            warnings.extend(auto.warnings.iter().map(|w| Warning {
                code: w.code,
                message: format!("{}: {}", est.name, w.message),
            }));
            let searched = Searched {
                methods,
                reason: auto.decision.reason.clone(),
                implied_lever: auto.decision.implied_lever_arm_m,
            };
            (Some(Ok(auto.estimate)), searched)
        }
        None => {
            let searched = Searched {
                methods,
                reason: format!("--offset-method {}", method.as_str()),
                implied_lever: None,
            };
            (
                single.first().map(|(_, r)| r.as_ref().map(|o| *o)),
                searched,
            )
        }
    };
    let (report, w) = match chosen {
        Some(Ok(o)) if o.status == OffsetStatus::Ok => search.accepted_offset(&o, searched),
        Some(Err(e @ Error::NoOverlap { .. })) => return Err(clone_no_overlap(e, &est.label)),
        Some(Ok(o)) => match auto
            .is_some()
            .then(|| search.pose_rescued(&o, &searched, Rescue::Weak))
            .flatten()
        {
            Some(rescued) => rescued,
            None => search.weak_offset(Some(&o), searched),
        },
        _ => search.weak_offset(None, searched),
    };
    // The signal searches' lever warnings say "measure the lever": the pose fit did, and the Δt it
    // applies does not rest on their lead. They stand where it could not tell a forward lever from
    // Δt (its σ then carries that), or did not run or converge; the reason keeps what the searches
    // saw.
    if report.fitted_forward_separable == Some(true) {
        warnings.retain(|w| !w.code.is_lever());
    }
    warnings.extend(w);
    Ok((report, warnings))
}

/// What every step of one estimate's time offset works on: the run's configuration, the searches'
/// parameters, the reference and the estimate paired (their signals computed once), the estimate,
/// and the instant its times count from. Built once by [`searched_offset`]; the steps (accept,
/// refine by the pose fit, rescue, report weak, model over time) are its methods.
struct OffsetSearch<'a> {
    config: &'a EvalConfig,
    params: &'a OffsetParams,
    pair: &'a Pair<'a>,
    est: &'a Loaded,
    /// The instant the trajectories' times count from, seconds since the epoch.
    t0_s: f64,
    /// Where the estimate jumps ([`crate::align::jumps::jumps`]), found once for every pose fit
    /// (a rescue or a fallback makes several).
    jumps: std::cell::OnceCell<Vec<(f64, f64)>>,
}

impl OffsetSearch<'_> {
    /// A confident answer: its clock model over time (refined by the pose fit under `auto` when the
    /// estimate has orientations), applied. Where the pose fit could be made neither from it nor
    /// from another confident search's answer, the weak searches' answers and the points between
    /// answers may start it ([`Self::pose_rescued`]: a speed search matched a walking robot's
    /// smooth speed 4.5 s from the truth, and the fit from there did not converge).
    fn accepted_offset(
        &self,
        o: &OffsetEstimate,
        searched: Searched,
    ) -> (TimeOffsetReport, Vec<Warning>) {
        let posed = self.pose_refined(o, &searched.methods, Starts::AnswerThenOthers);
        if posed.is_none() {
            if let Some(rescued) = self.pose_rescued(o, &searched, Rescue::ConfidentUnfitted) {
                return rescued;
            }
        }
        let Searched {
            mut methods,
            reason,
            implied_lever,
        } = searched;
        let (report, w, method, reason) = match posed {
            Some(Posed {
                report,
                warnings: w,
                note,
                entry,
                ..
            }) => {
                methods.push(entry);
                (report, w, OffsetMethod::Pose, format!("{reason}; {note}"))
            }
            None => {
                let (report, w) = self.over_time(o);
                (report, w, o.method, reason)
            }
        };
        (
            applied_report(report, method, o, methods, reason, implied_lever),
            w,
        )
    }

    /// The pose fit around the answer `o` (under `auto`, when the estimate has orientations), from
    /// where `starts` allows; with the default Newton Jacobian, else the narrow one where the
    /// default cannot make the fit (see [`crate::align::pose_fit::NARROW_JACOBIAN_PERIODS`]).
    fn pose_refined(
        &self,
        o: &OffsetEstimate,
        methods: &[OffsetMethodReport],
        starts: Starts,
    ) -> Option<Posed> {
        use crate::align::pose_fit::{JACOBIAN_PERIODS, NARROW_JACOBIAN_PERIODS};
        let q = self.est.trajectory.orientations.as_deref()?;
        if !self.config.pose_fit() {
            return None;
        }
        let attempt = |jacobian_periods: f64| {
            let pose_from = |start: &OffsetEstimate| {
                let fit = (q, jacobian_periods);
                self.pose_over_time(fit, start, methods)
            };
            pose_from(o).or_else(|| match starts {
                Starts::AnswerThenOthers => pose_from_another_answer(o, methods, pose_from),
                Starts::AnswerOnly => None,
            })
        };
        attempt(JACOBIAN_PERIODS).or_else(|| attempt(NARROW_JACOBIAN_PERIODS))
    }

    /// No search was confident enough to be applied (`answer`, the best), or one was (`answer`) but the
    /// pose fit could be made neither from its answer nor from another confident search's
    /// (`rescue`; those are not tried again): the pose fit started
    /// from each search's answer and from points between answers beyond its reach of each other
    /// ([`rescue_starts`]; on near-straight paths the speed search was within a few
    /// milliseconds where its peak was too flat to be confident, and the curvature searches there
    /// are noise; on walking robots a confident speed search matched at a wrong lag contradicts
    /// signed curvature's lead). A fit counts when it converged with its lever (its σ has its
    /// parts), tells the forward lever from Δt (at a constant speed nothing does, and the answer
    /// stays weak) or, where the lever inflates Δt's variance beyond the inseparable mark, still
    /// pins Δt within [`RESCUE_SIGMA_S`] with the lever fitted, and stayed within
    /// [`MAX_DISAGREEMENT_S`] of its start or the lead search, which judges the basins it compares
    /// on every window, moved it; of those, the one with the least mean squared residual over its
    /// windows is applied, the reason saying where it started. `None` when none counts.
    ///
    /// [`MAX_DISAGREEMENT_S`]: crate::align::pose_model::MAX_DISAGREEMENT_S
    fn pose_rescued(
        &self,
        answer: &OffsetEstimate,
        searched: &Searched,
        rescue: Rescue,
    ) -> Option<(TimeOffsetReport, Vec<Warning>)> {
        use crate::align::pose_model::MAX_DISAGREEMENT_S;
        if !self.config.pose_fit() {
            return None;
        }
        let answers: Vec<(OffsetMethod, f64)> = searched
            .methods
            .iter()
            .filter(|m| m.status != MethodStatus::Failed)
            .filter_map(|m| Some((m.method, m.offset_s.filter(|o| o.is_finite())?)))
            .collect();
        // The confident searches' answers were tried already where the confident answer could not
        // start the fit (`Starts::AnswerThenOthers`).
        let tried = |start: &RescueStart| match (rescue, start) {
            (Rescue::ConfidentUnfitted, RescueStart::Answer(m)) => searched
                .methods
                .iter()
                .any(|r| r.method == *m && r.status == MethodStatus::Ok),
            _ => false,
        };
        let (start, offset_s, posed) = rescue_starts(&answers)
            .into_iter()
            .filter(|(start, _)| !tried(start))
            .filter_map(|(start, offset_s)| {
                let estimate = OffsetEstimate {
                    method: start.method(),
                    offset_s,
                    status: OffsetStatus::Ok,
                    ..*answer
                };
                let posed = self.pose_refined(&estimate, &searched.methods, Starts::AnswerOnly)?;
                let near = (posed.report.offset_s - offset_s).abs() <= MAX_DISAGREEMENT_S;
                let told = pins_offset(posed.report.fitted_forward_separable, posed.report.sigma_s);
                (posed.report.sigma_parts.is_some() && told && (near || posed.lead_moved))
                    .then_some((start, offset_s, posed))
            })
            .min_by(|a, b| a.2.mse_m2.total_cmp(&b.2.mse_m2))?;
        let mut methods = searched.methods.clone();
        methods.push(posed.entry);
        let fit = match rescue {
            Rescue::Weak => "the pose fit",
            Rescue::ConfidentUnfitted => {
                "the pose fit could be made neither from that answer nor from another confident search's, and the one"
            }
        };
        let reason = format!(
            "{}; but {fit} started from {start} ({offset_s:+.3} s) converged with its lever and fits the windows best of the starts tried: {}",
            searched.reason, posed.note
        );
        let report = applied_report(
            posed.report,
            OffsetMethod::Pose,
            answer,
            methods,
            reason,
            searched.implied_lever,
        );
        Some((report, posed.warnings))
    }

    /// No confident peak: nothing applied (0 s), the best answer reported, and a warning saying
    /// what to do.
    fn weak_offset(
        &self,
        best: Option<&OffsetEstimate>,
        searched: Searched,
    ) -> (TimeOffsetReport, Vec<Warning>) {
        let (method, offset_s, correlation, confidence) = match best {
            Some(o) => (
                o.method,
                o.offset_s,
                Some(o.correlation),
                Some(o.confidence),
            ),
            None => (self.config.params.offset_method(), 0.0, None, None),
        };
        let hint = if self.config.params.offset_method() == OffsetMethod::Auto {
            format!(
                "{}. Check the overlap or give --time-offset",
                searched.reason
            )
        } else {
            "Check the overlap, try --offset-method auto or give --time-offset".into()
        };
        let warning = Warning {
            code: WarningCode::WeakTimeOffset,
            message: format!(
                "{}: the {} time-offset peak is weak (best {:+.3} s); Drift Error computed at 0 s. {}",
                self.est.name,
                method.as_str(),
                offset_s,
                hint
            ),
        };
        let report = TimeOffsetReport {
            method: method.into(),
            offset_s,
            applied_s: 0.0,
            correlation,
            confidence,
            status: TimeOffsetStatus::Weak,
            methods: searched.methods,
            reason: Some(searched.reason),
            implied_lever_arm_m: searched.implied_lever,
            ..Default::default()
        };
        (report, vec![warning])
    }

    /// The clock model from the pose fit ([`crate::align::pose_model`]) around the signal searches'
    /// answer `o` (the other confident searches' answers in `methods` widen its lead search), on
    /// the estimate's `orientations` with the Newton Jacobian `jacobian_periods` wide
    /// ([`crate::align::pose_fit::PoseFitParams::jacobian_periods`]; the note says when it is not
    /// the default): the report's fields, the warnings of a non-constant model chosen from the
    /// data, the note for the reason, and the `pose` entry of `methods`. `None` when the fit cannot
    /// be made (the signal searches' profile is used instead).
    fn pose_over_time(
        &self,
        (orientations, jacobian_periods): (&[nalgebra::UnitQuaternion<f64>], f64),
        o: &OffsetEstimate,
        methods: &[OffsetMethodReport],
    ) -> Option<Posed> {
        use crate::align::pose_model::pose_clock_model;
        // The other confident searches' answers: the lead search scans about them too.
        let other_answers_s: Vec<f64> = confident_answers(methods, o.method)
            .map(|(_, offset_s)| offset_s)
            .collect();
        let gap_s = self
            .params
            .max_gap_s
            .unwrap_or(self.params.curvature.dt_max_s);
        let jumps = self.jumps.get_or_init(|| {
            crate::align::jumps::jumps(self.pair.estimate.0, self.pair.estimate.1, gap_s)
        });
        let mut data = pose_data(self.pair, orientations, jumps, gap_s);
        data.params.jacobian_periods = jacobian_periods;
        // The speed signals locate a step's time when the positions do not (computed already by
        // `auto`; otherwise only when asked).
        let speed = std::cell::OnceCell::new();
        let cell = &speed;
        let signals = move || {
            cell.get_or_init(|| {
                crate::align::time_offset::prepared_signals(
                    OffsetMethod::Speed,
                    self.pair,
                    self.params,
                    o.offset_s,
                )
                .ok()
            })
            .as_ref()
            .map(speed_views)
        };
        let pc = pose_clock_model(
            &data,
            o.offset_s,
            &other_answers_s,
            &self.config.params.offset_profile(),
            &signals,
            self.config.params.forced_offset_model(),
        )?;
        let model = &pc.model;
        let mut warnings = model_warnings(self.config, model, &self.est.name);
        warnings.extend(
            pc.beyond_lever
                .map(|b| long_lever_warning(&self.est.name, &pc, b)),
        );
        let (lever, lever_sigma) = pc.lever;
        let report = TimeOffsetReport {
            fitted_lever_m: Some([lever.x, lever.y, lever.z]),
            fitted_lever_sigma_m: lever_sigma.map(|s| [s.x, s.y, s.z]),
            fitted_forward_separable: pc.fit.as_ref().map(|f| !f.inseparable()),
            sigma_parts: pc.sigma_parts,
            ..model_report(model, &pc.profile, self.t0_s)
        };
        let mut note = pose_note(&pc);
        if jacobian_periods < crate::align::pose_fit::JACOBIAN_PERIODS {
            note.push_str(&format!(
                "; Newton stepped on a Jacobian {jacobian_periods:.0} of the estimate's periods beyond the differences, not the default {:.0}, with which the fit could not be made (over that reach a gait's bob can turn it negative)",
                crate::align::pose_fit::JACOBIAN_PERIODS
            ));
        }
        let mse_m2 = pc.fit.as_ref().map_or(f64::INFINITY, |f| {
            f.rms_m.iter().map(|r| r * r).sum::<f64>() / f.rms_m.len().max(1) as f64
        });
        Some(Posed {
            report,
            warnings,
            note,
            entry: pose_entry(&pc),
            mse_m2,
            lead_moved: pc.replaced.is_some(),
        })
    }

    /// The offset profile of the applied method around its whole-mission answer `o`, the clock
    /// model (chosen or `--offset-model`), its report fields and the warnings of a non-constant
    /// model chosen from the data. On a mission too short for a profile: a constant model and no
    /// profile.
    fn over_time(&self, o: &OffsetEstimate) -> (TimeOffsetReport, Vec<Warning>) {
        let found = clock_model_of(
            self.pair,
            self.params,
            o,
            &self.config.params.offset_profile(),
            self.config.params.forced_offset_model(),
        );
        let Ok((profile, model)) = found else {
            let reason = "constant: no offset profile (too short an overlap)".to_string();
            return (
                TimeOffsetReport {
                    offset_s: o.offset_s,
                    sigma_s: o.sigma_s,
                    model: Some(OffsetModel::Constant),
                    model_reason: Some(reason),
                    ..Default::default()
                },
                Vec::new(),
            );
        };
        let warnings = model_warnings(self.config, &model, &self.est.name);
        (model_report(&model, &profile, self.t0_s), warnings)
    }
}

/// `report` (the clock model's fields) as the applied answer of `method`: its offset applied, the
/// searches' `methods`, the `reason`, and the peak of the search answer `o` it came from.
fn applied_report(
    report: TimeOffsetReport,
    method: OffsetMethod,
    o: &OffsetEstimate,
    methods: Vec<OffsetMethodReport>,
    reason: String,
    implied_lever: Option<f64>,
) -> TimeOffsetReport {
    TimeOffsetReport {
        method: method.into(),
        applied_s: report.offset_s,
        correlation: Some(o.correlation),
        confidence: Some(o.confidence),
        status: TimeOffsetStatus::Ok,
        methods,
        reason: Some(reason),
        implied_lever_arm_m: implied_lever,
        ..report
    }
}

/// A weak search is rescued by a pose fit whose lever inflates Δt's variance beyond
/// [`crate::align::pose_fit::INSEPARABLE_VIF`] when its σ, the lever fitted, is within this,
/// seconds: the σ already carries what the lever could move Δt by, so a narrow one is an answer
/// (a vehicle on a 1 Hz reference, before its windows' scale was held at 30 m: inflation 26, σ
/// 11 ms, 0.8 ms off, where applying nothing left it 15 ms off and reported the curvature search's
/// −74 ms; the rule is [`pins_offset`]; docs/evidence.md, "A weak search
/// rescued where the lever inflates σ but leaves it narrow"). A straight line at a constant speed
/// still stays weak (the command line's test `weak_offset_exits_3_and_still_writes_json`).
const RESCUE_SIGMA_S: f64 = 0.05;

/// Whether a pose fit pins Δt well enough to rescue a weak search: it tells the forward lever from
/// Δt (`separable`), or its σ with the lever fitted is within [`RESCUE_SIGMA_S`].
///
/// ```text
/// separable, any σ → yes; inseparable, σ 11 ms → yes; inseparable, σ 0.2 s → no; no σ → no
/// ```
fn pins_offset(separable: Option<bool>, sigma_s: Option<f64>) -> bool {
    separable == Some(true) || sigma_s.is_some_and(|s| s <= RESCUE_SIGMA_S)
}

/// Where a rescue's pose fit starts: a search's answer, or a point between two answers that lie
/// beyond the fit's reach of each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RescueStart {
    /// The answer of this search.
    Answer(OffsetMethod),
    /// A point between the answers of these two searches.
    Between(OffsetMethod, OffsetMethod),
}

impl RescueStart {
    /// The search the start is counted to (the lead search leaves its answer out of the others).
    fn method(self) -> OffsetMethod {
        match self {
            RescueStart::Answer(m) | RescueStart::Between(m, _) => m,
        }
    }
}

impl std::fmt::Display for RescueStart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RescueStart::Answer(m) => write!(f, "{m}'s answer"),
            RescueStart::Between(a, b) => write!(f, "between {a}'s and {b}'s answers"),
        }
    }
}

/// The most points a rescue starts from between two searches' answers: answers up to
/// 2 × ([`RESCUE_FILL_STARTS`] + 1) × [`MAX_DISAGREEMENT_S`] (2.4 s) apart are bridged; farther
/// apart, one is a lever read as a lead or a profile matched at a wrong lag, and the truth lies
/// near one of them.
///
/// [`MAX_DISAGREEMENT_S`]: crate::align::pose_model::MAX_DISAGREEMENT_S
const RESCUE_FILL_STARTS: usize = 3;

/// Where a weak search's rescue starts the pose fit, from the searches' `answers` (method, Δt):
/// each answer not within [`MAX_DISAGREEMENT_S`] of an earlier one, and, between two neighbouring
/// starts farther apart than twice that (and at most [`RESCUE_FILL_STARTS`] + 1 times farther),
/// points evenly spaced so that every Δt between them lies within the fit's reach of a start. Two
/// weak searches may both miss by more than the reach on either side (a vehicle on a 20 Hz
/// reference with GNSS outages: speed −0.382 s, curvature +0.317 s, the truth −0.015 s);
/// the fits from every start are then judged by their residual.
///
/// ```text
/// speed −0.382, signed curvature +0.318, curvature +0.317
///   → speed's answer −0.382, signed curvature's +0.318, between the two −0.032
/// speed 0.0, curvature 5.0 → the two answers only (too far apart to bridge)
/// ```
///
/// [`MAX_DISAGREEMENT_S`]: crate::align::pose_model::MAX_DISAGREEMENT_S
fn rescue_starts(answers: &[(OffsetMethod, f64)]) -> Vec<(RescueStart, f64)> {
    use crate::align::pose_model::MAX_DISAGREEMENT_S;
    let mut kept: Vec<(OffsetMethod, f64)> = Vec::new();
    for &(method, offset_s) in answers {
        if !kept
            .iter()
            .any(|(_, s)| (s - offset_s).abs() <= MAX_DISAGREEMENT_S)
        {
            kept.push((method, offset_s));
        }
    }
    let mut starts: Vec<(RescueStart, f64)> = kept
        .iter()
        .map(|&(m, offset_s)| (RescueStart::Answer(m), offset_s))
        .collect();
    kept.sort_by(|a, b| a.1.total_cmp(&b.1));
    for pair in kept.windows(2) {
        let ((a, lo_s), (b, hi_s)) = (pair[0], pair[1]);
        let pieces = ((hi_s - lo_s) / (2.0 * MAX_DISAGREEMENT_S)).ceil() as usize;
        if (2..=RESCUE_FILL_STARTS + 1).contains(&pieces) {
            let step_s = (hi_s - lo_s) / pieces as f64;
            starts.extend(
                (1..pieces).map(|k| (RescueStart::Between(a, b), lo_s + k as f64 * step_s)),
            );
        }
    }
    starts
}

/// Why a rescue's pose fit is started from the searches' answers ([`OffsetSearch::pose_rescued`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rescue {
    /// No search was confident.
    Weak,
    /// A search was confident, but the fit could be made neither from its answer nor from another
    /// confident search's (those are not tried again).
    ConfidentUnfitted,
}

/// Where the pose fit may start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Starts {
    /// From the answer given, else from another confident search's (`pose_from_another_answer`).
    AnswerThenOthers,
    /// From the answer given only (the caller tries the others itself).
    AnswerOnly,
}

/// The pose fit from another confident search's answer, when it could not be made from the one
/// applied (`o`) and that one lies beyond the fit's reach ([`MAX_DISAGREEMENT_S`]): two searches
/// that disagree by seconds are a lever read as a lead by one of them, or a speed profile matched
/// at a wrong lag, and the positions tell which only from a start near the truth (or within the
/// lead search's reach). `pose_from` makes the pose fit from a start; its answer is accepted only
/// when the fit converged with its lever (its σ has its parts), the note saying where it started.
///
/// [`MAX_DISAGREEMENT_S`]: crate::align::pose_model::MAX_DISAGREEMENT_S
fn pose_from_another_answer(
    o: &OffsetEstimate,
    methods: &[OffsetMethodReport],
    pose_from: impl Fn(&OffsetEstimate) -> Option<Posed>,
) -> Option<Posed> {
    use crate::align::pose_model::MAX_DISAGREEMENT_S;
    confident_answers(methods, o.method)
        .filter(|(_, offset_s)| (offset_s - o.offset_s).abs() > MAX_DISAGREEMENT_S)
        .find_map(|(method, offset_s)| {
            let start = OffsetEstimate {
                method,
                offset_s,
                ..*o
            };
            let posed = pose_from(&start)?;
            posed.report.sigma_parts.is_some().then(|| Posed {
                note: format!(
                    "the pose fit could not be made from {}'s answer and started from {}'s ({:+.3} s): {}",
                    o.method, method, offset_s, posed.note
                ),
                ..posed
            })
        })
}

/// What the pose fit gives the report, and what tells two fits from different starts apart.
struct Posed {
    /// The report's fields.
    report: TimeOffsetReport,
    /// The warnings of a non-constant model.
    warnings: Vec<Warning>,
    /// The note for the reason.
    note: String,
    /// The `pose` entry of `methods`.
    entry: OffsetMethodReport,
    /// The final fit's mean squared residual over its windows, m² (∞ without a final fit).
    mse_m2: f64,
    /// Whether the lead search moved the answer from the basin of the start.
    lead_moved: bool,
}

/// The answers of the confident searches in `methods` other than `except`: (method, Δt).
fn confident_answers(
    methods: &[OffsetMethodReport],
    except: OffsetMethod,
) -> impl Iterator<Item = (OffsetMethod, f64)> + '_ {
    methods
        .iter()
        .filter(move |m| m.status == MethodStatus::Ok && m.method != except)
        .filter_map(|m| Some((m.method, m.offset_s?)))
}

/// Names the estimate in an overlap error raised deep in the maths.
pub(super) fn relabel(e: Error, label: &str) -> Error {
    match e {
        Error::NoOverlap { .. } => clone_no_overlap(&e, label),
        Error::TooFewSamples { n, need, what } => Error::TooFewSamples {
            what: format!("{label}: {what}"),
            n,
            need,
        },
        other => other,
    }
}

fn clone_no_overlap(e: &Error, label: &str) -> Error {
    match e {
        Error::NoOverlap {
            est_start,
            est_end,
            ref_start,
            ref_end,
            offset,
            ..
        } => Error::NoOverlap {
            estimate: label.to_string(),
            est_start: *est_start,
            est_end: *est_end,
            ref_start: *ref_start,
            ref_end: *ref_end,
            offset: *offset,
        },
        _ => Error::InvalidArgument(e.to_string()),
    }
}

/// What the pose fit works on: the pair's positions, the estimate's `orientations` and `jumps`, its
/// gaps bounded like the signal searches' (their `max_gap_s`, else the curvature's Δt_max).
fn pose_data<'a>(
    pair: &Pair<'a>,
    orientations: &'a [nalgebra::UnitQuaternion<f64>],
    jumps: &'a [(f64, f64)],
    max_gap_s: f64,
) -> crate::align::pose_fit::PoseData<'a> {
    use crate::align::pose_fit::{PoseData, PoseFitParams, PoseTrack};
    let (ref_t, ref_p) = pair.reference;
    let (est_t, est_p) = pair.estimate;
    PoseData {
        ref_t,
        ref_p,
        estimate: PoseTrack {
            t: est_t,
            p: est_p,
            q: orientations,
            jumps,
        },
        // The pose clock model chooses the window and the scale prior for the mission.
        params: PoseFitParams::new(max_gap_s),
    }
}

/// The speed search's signals as the pose fit's views, the estimate's moved by the lateral lever the
/// speed search found (if any).
fn speed_views(
    ((r, e), lever): &(crate::align::time_offset::SignalPair, Option<f64>),
) -> (
    crate::align::time_offset::SignalView<'_>,
    crate::align::time_offset::SignalView<'_>,
) {
    use crate::align::time_offset::SignalView;
    let e = match lever {
        Some(d) => SignalView::with_lever(e, *d),
        None => SignalView::of(e),
    };
    (SignalView::of(r), e)
}

/// The reason's note on the pose fit: its windows, its first clock parameter (the constant, the
/// line's offset at t_mid or the first segment's) with its σ, its lever, the windows left
/// out as jumps, and when the lever and Δt are inseparable (locally, or between two fits along the
/// forward lever's valley).
fn pose_note(pc: &crate::align::pose_model::PoseClock) -> String {
    let (lever, _) = pc.lever;
    let mut note = format!(
        "refined by the pose fit ({} windows of {:.0} s: Δt {:+.4} ± {:.4} s, the estimate's sensor at ({:+.2}, {:+.2}, {:+.2}) m from the reference's point, fitted alongside)",
        pc.profile.windows.len(),
        pc.profile.window_s,
        pc.first_offset.0,
        pc.first_offset.1,
        lever.x,
        lever.y,
        lever.z
    );
    if let Some(r) = pc.replaced {
        note.push_str(&format!(
            "; the windows started from that answer chose {} ({:+.3} s first), but the lead search found this constant {:+.3} s away, fitting the referee's longer windows better, and its own windows choose a constant too{}",
            r.model.as_str(),
            r.first_s,
            pc.first_offset.0 - r.first_s,
            if r.narrow_windows {
                format!(
                    " (measured on a Jacobian {:.0} of the estimate's periods beyond the differences: on the default {:.0}, fewer than three of them could be fitted)",
                    crate::align::pose_fit::NARROW_JACOBIAN_PERIODS,
                    crate::align::pose_fit::JACOBIAN_PERIODS
                )
            } else {
                String::new()
            }
        ));
    }
    if let Some(b) = pc.beyond_lever {
        note.push_str(&format!(
            "; a fit at {:+.3} s fits the referee's longer windows better but needs the sensor {:+.2} m ahead along the direction of travel, beyond what a walking robot's lead search allows for: left out (long_lever_left_out)",
            b.offset_s, b.forward_m,
        ));
    }
    if pc.outlier_windows > 0 {
        note.push_str(&format!(
            "; {} window(s) left out: the estimate jumps there (a position correction, not a clock event)",
            pc.outlier_windows
        ));
    }
    if let Some(valley_s) = pc.sigma_parts.map(|p| p.valley_s).filter(|v| *v > 0.0) {
        note.push_str(&format!(
            "; a fit {:.2} s away, the sensor moved along the direction of travel, fits the referee's longer windows about as well (a forward lever and Δt trade at a steady walk): σ covers it",
            2.0 * valley_s
        ));
    } else if pc.fit.as_ref().is_some_and(|f| f.inseparable()) {
        note.push_str(
            "; at this mission's nearly constant speed a forward lever and Δt are inseparable: σ says how much",
        );
    }
    note
}

/// The warning that a fit needing a longer forward lever than the lead search allows for
/// (`b`) fits the windows better than the one applied: Δt holds only if the sensors are within
/// [`LEAD_LEVER_M`] of each other along the travel.
///
/// [`LEAD_LEVER_M`]: crate::align::pose_model::LEAD_LEVER_M
fn long_lever_warning(
    name: &str,
    pc: &crate::align::pose_model::PoseClock,
    b: crate::align::pose_model::BeyondLever,
) -> Warning {
    Warning::new(
        WarningCode::LongLeverLeftOut,
        format!(
            "{name}: a clock offset of {:+.3} s with the sensor {:+.2} ± {:.2} m ahead of the reference's point fits better than the {:+.3} s applied, which assumes the two within {:.1} m along the direction of travel; if they sit farther apart, give --estimate-lever and --reference-lever",
            b.offset_s,
            b.forward_m,
            b.forward_sigma_m,
            pc.first_offset.0,
            crate::align::pose_model::LEAD_LEVER_M
        ),
    )
}

/// The pose fit's row of `methods`: its first clock parameter and its windows' median correlation.
fn pose_entry(pc: &crate::align::pose_model::PoseClock) -> OffsetMethodReport {
    OffsetMethodReport {
        method: OffsetMethod::Pose,
        offset_s: Some(pc.first_offset.0),
        correlation: crate::align::offset_profile::median(
            &pc.profile
                .windows
                .iter()
                .map(|w| w.correlation)
                .collect::<Vec<_>>(),
        ),
        confidence: None,
        status: MethodStatus::Ok,
        error: None,
        margin: None,
        defined_fraction: None,
    }
}

/// The warnings of a non-constant clock model chosen from the data (none when one was forced).
fn model_warnings(
    config: &EvalConfig,
    model: &crate::align::clock_model::ClockModel,
    name: &str,
) -> Vec<Warning> {
    let code = match model.model {
        OffsetModel::Linear => WarningCode::ClockDriftSuspected,
        OffsetModel::Piecewise => WarningCode::ClockStepSuspected,
        OffsetModel::Constant => return Vec::new(),
    };
    if config.params.forced_offset_model().is_some() {
        return Vec::new();
    }
    vec![Warning {
        code,
        message: format!(
            "{name}: the clock offset is not constant — {}; the estimate's stamps were corrected by this model (force one with --offset-model)",
            model.reason
        ),
    }]
}

/// A clock model and its offset profile as the report's fields (times absolute: `t0_s` added).
fn model_report(
    model: &crate::align::clock_model::ClockModel,
    profile: &crate::align::offset_profile::OffsetProfile,
    t0_s: f64,
) -> TimeOffsetReport {
    TimeOffsetReport {
        offset_s: model.offset_s,
        sigma_s: Some(model.sigma_s),
        model: Some(model.model),
        model_reason: Some(model.reason.clone()),
        drift_measured_ppm: model.drift_ppm,
        drift_sigma_ppm: model.drift_sigma_ppm,
        drift_ppm: model
            .drift_ppm
            .filter(|_| model.model == OffsetModel::Linear),
        t_mid: (model.model == OffsetModel::Linear).then_some(model.t_mid + t0_s),
        drift_resolution_ppm: model.drift_resolution_ppm,
        segments: model
            .segments
            .iter()
            .map(|s| OffsetSegmentReport {
                t_start: s.t_start + t0_s,
                t_end: s.t_end + t0_s,
                offset_s: s.offset_s,
                sigma_s: s.sigma_s,
            })
            .collect(),
        profile: profile
            .windows
            .iter()
            .map(|w| OffsetProfilePoint {
                t: w.t + t0_s,
                offset_s: w.offset_s,
                sigma_s: w.sigma_s,
                correlation: w.correlation,
            })
            .collect(),
        profile_window_s: Some(profile.window_s),
        profile_step_s: Some(profile.step_s),
        ..Default::default()
    }
}

#[cfg(test)]
mod rescue_tests {
    use super::{pins_offset, rescue_starts, RescueStart};

    #[test]
    fn an_inseparable_fit_rescues_only_under_a_narrow_sigma() {
        assert!(pins_offset(Some(true), Some(0.3)));
        assert!(pins_offset(Some(false), Some(0.011)));
        assert!(!pins_offset(Some(false), Some(0.2)));
        assert!(!pins_offset(Some(false), None));
        assert!(!pins_offset(None, Some(f64::NAN)));
    }

    #[test]
    fn a_rescue_starts_between_answers_beyond_the_fits_reach() {
        use super::OffsetMethod::{Curvature, SignedCurvature, Speed};
        let starts = rescue_starts(&[
            (Speed, -0.382),
            (SignedCurvature, 0.3178),
            (Curvature, 0.317),
        ]);
        assert_eq!(starts.len(), 3);
        assert_eq!(starts[0], (RescueStart::Answer(Speed), -0.382));
        assert_eq!(starts[1], (RescueStart::Answer(SignedCurvature), 0.3178));
        assert_eq!(starts[2].0, RescueStart::Between(Speed, SignedCurvature));
        assert!((starts[2].1 - -0.0321).abs() < 1e-12);
        // Within twice the reach: the answers cover every Δt between them.
        assert_eq!(rescue_starts(&[(Speed, 0.0), (Curvature, 0.55)]).len(), 2);
        // 1.5 s apart: two points between, every Δt within 0.3 s of a start.
        let bridged = rescue_starts(&[(Curvature, 1.0), (Speed, -0.5)]);
        let between: Vec<f64> = bridged[2..].iter().map(|s| s.1).collect();
        assert_eq!(between.len(), 2);
        assert!((between[0] - 0.0).abs() < 1e-12 && (between[1] - 0.5).abs() < 1e-12);
        // Too far apart to bridge: the answers only.
        assert_eq!(rescue_starts(&[(Speed, 0.0), (Curvature, 5.0)]).len(), 2);
    }
}
