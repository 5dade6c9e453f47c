//! The answer a profile gives, and the Pareto fronts it is chosen from:
//! decisions over the measured rows, which the report then shows.

use crate::report::{Budget, Choice, Confirmation, Report, ResultRow};

/// Marks the rows on the Pareto front of GPU time against PSNR, and
/// against SSIM: those no other configuration beats on one without losing
/// on the other. The unmodified shader counts as a point (its time, an
/// exact image), so a configuration slower than the original is never on
/// a front. Time is each row's against its own reference (1 / speed-up):
/// within one run the same order as its milliseconds, and across the
/// shards of a sweep ([`super::merge`]), each run on its own machine, the
/// only comparable one.
pub fn mark_pareto_fronts(rows: &mut [ResultRow]) {
    let front = |metric: fn(&ResultRow) -> f64, exact: f64| -> Vec<bool> {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (1.0 / r.speedup, metric(r)))
            .chain([(1.0, exact)])
            .collect();
        let dominated = |&(t, m): &(f64, f64)| {
            points
                .iter()
                .any(|&(u, n)| u <= t && n >= m && (u < t || n > m))
        };
        points[..rows.len()].iter().map(|p| !dominated(p)).collect()
    };
    let psnr = front(|r| r.psnr, f64::INFINITY);
    let ssim = front(|r| r.ssim, 1.0);
    for ((row, on_psnr), on_ssim) in rows.iter_mut().zip(psnr).zip(ssim) {
        row.pareto_psnr = on_psnr;
        row.pareto_ssim = on_ssim;
    }
}

impl Report {
    /// The answer from this run: the fastest configuration within
    /// `budget` whose speed-up interval lies above 1×, or none, with what
    /// came closest. The caller measures the winner again and settles the
    /// answer with [`Choice::confirm`].
    pub fn choose(&self, budget: Budget, budget_given: bool) -> Choice {
        let rows = &self.results;
        let faster = |i: &usize| rows[*i].speedup_ci[0] > 1.0;
        // The fastest by speed-up: within one run the least time, and
        // across merged shards the only comparable measure.
        let fastest = |among: &mut dyn Iterator<Item = usize>| {
            among.min_by(|&a, &b| rows[b].speedup.total_cmp(&rows[a].speedup))
        };
        let within: Vec<usize> = (0..rows.len())
            .filter(|&i| budget.admits(&rows[i]))
            .collect();
        let winner = fastest(&mut within.iter().copied().filter(faster));
        let mut choice = Choice {
            budget,
            budget_given,
            result: winner,
            none_within_budget: within.is_empty(),
            closest: None,
            confirmation: None,
            reason: String::new(),
        };
        // Nothing measured on a reference that shows nothing is an answer.
        if let Some(check) = self.reference_check.as_ref().filter(|c| c.degenerate()) {
            let findings: Vec<&str> = check.problems.iter().map(|p| p.finding.as_str()).collect();
            choice.result = None;
            choice.closest = None;
            choice.reason = format!(
                "no answer: the reference is degenerate ({}), so every configuration's error is measured against frames that show nothing of the shader; fix the scene (see the reference check) and profile again",
                findings.join("; ")
            );
            return choice;
        }
        if let Some(i) = winner {
            choice.reason = format!(
                "the fastest of the {} configurations within {budget} whose speed-up interval lies above 1×: {}",
                within.len(),
                self.measured(&rows[i])
            );
            return choice;
        }
        // What came closest: within the budget, the fastest; else, of those
        // reliably faster, the least error; else the fastest of all.
        choice.closest = if within.is_empty() {
            (0..rows.len())
                .filter(faster)
                .max_by(|&a, &b| budget.metric(&rows[a]).total_cmp(&budget.metric(&rows[b])))
                .or_else(|| fastest(&mut (0..rows.len())))
        } else {
            fastest(&mut within.iter().copied())
        };
        let mut closest = choice
            .closest
            .map(|i| format!(" Closest: {}.", self.how_far(&rows[i], budget)))
            .unwrap_or_default();
        // Within the budget but slower: the next thing to try is the most
        // accurate of those reliably faster, with how far it falls short.
        if !within.is_empty() {
            // The most accurate, and of equally accurate ones the fastest.
            let faster_over_budget = (0..rows.len()).filter(faster).max_by(|&a, &b| {
                budget
                    .metric(&rows[a])
                    .total_cmp(&budget.metric(&rows[b]))
                    .then(rows[a].speedup.total_cmp(&rows[b].speedup))
            });
            if let Some(i) = faster_over_budget {
                closest.push_str(&format!(
                    " Faster but over the budget: {}.",
                    self.how_far(&rows[i], budget)
                ));
            }
        }
        choice.reason = if rows.is_empty() {
            "no configuration could be measured: keep the original shader".into()
        } else if within.is_empty() {
            format!(
                "none of the {} configurations is within {budget}: keep the original shader.{closest}",
                rows.len()
            )
        } else {
            format!(
                "{} within {budget}, but none is faster than the original beyond this run's noise (a speed-up interval above 1×): keep the original shader.{closest}",
                match within.len() {
                    1 => "1 configuration is".to_string(),
                    n => format!("{n} configurations are"),
                }
            )
        };
        choice
    }

    /// A row in words, with how far it is from an answer: slower than the
    /// original by how much, short of the budget by how much.
    fn how_far(&self, row: &ResultRow, budget: Budget) -> String {
        let mut words = self.measured(row);
        let mut gaps = Vec::new();
        if row.speedup_ci[0] <= 1.0 {
            gaps.push(if row.speedup < 1.0 && row.speedup > 0.0 {
                format!("{:.1}× slower than the original", 1.0 / row.speedup)
            } else {
                "not reliably faster than the original".to_string()
            });
        }
        if !budget.admits(row) {
            gaps.push(match budget {
                Budget::Psnr(db) => format!("{:.1} dB short of {budget}", db - row.psnr),
                Budget::Ssim(ssim) => format!("SSIM {:.4} short of {budget}", ssim - row.ssim),
            });
        }
        if !gaps.is_empty() {
            words.push_str(&format!(" ({})", gaps.join("; ")));
        }
        words
    }

    /// A row in words: node, variant, knobs, speed-up with its interval,
    /// error.
    pub fn measured(&self, row: &ResultRow) -> String {
        format!(
            "node {} `{}`, {}, {}: {:.3} ms against {:.3} ms for the original, {:.2}× [{:.2}, {:.2}], PSNR {:.1} dB, SSIM {:.4}",
            row.node,
            row.node_text,
            row.variant,
            row.setting(),
            row.time_ms,
            self.reference.time_ms,
            row.speedup,
            row.speedup_ci[0],
            row.speedup_ci[1],
            row.psnr,
            row.ssim
        )
    }
}

impl Choice {
    /// Settles the answer with the winner measured again: it stands only
    /// when that run's interval lies above 1× as well.
    pub fn confirm(&mut self, confirmation: Confirmation) {
        let again = format!(
            "measured again over {} frames, {:.3} ms against {:.3} ms, {:.2}× [{:.2}, {:.2}]",
            confirmation.frames,
            confirmation.time_ms,
            confirmation.reference_ms,
            confirmation.speedup,
            confirmation.speedup_ci[0],
            confirmation.speedup_ci[1]
        );
        if confirmation.speedup_ci[0] > 1.0 {
            self.reason = format!("{}; {again}", self.reason);
        } else {
            self.closest = self.result.take();
            self.reason = format!(
                "the run's winner ({}) is not faster than the original when {again}: keep the original shader",
                self.reason
            );
        }
        self.confirmation = Some(confirmation);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::{report, row};
    use crate::report::*;

    #[test]
    fn the_front_keeps_the_rows_nothing_beats_on_both() {
        // Reference 10 ms. (5, 30) and (7, 35) trade off; (6, 29) loses to
        // (5, 30) on both; (8, 35) ties (7, 35) on PSNR but is slower;
        // (12, 40) is slower than the exact original.
        let mut rows = vec![
            row(5.0, 30.0, 0.90),
            row(6.0, 29.0, 0.95),
            row(7.0, 35.0, 0.93),
            row(8.0, 35.0, 0.99),
            row(12.0, 40.0, 0.999),
        ];
        mark_pareto_fronts(&mut rows);
        let psnr: Vec<bool> = rows.iter().map(|r| r.pareto_psnr).collect();
        assert_eq!(psnr, [true, false, true, false, false]);
        let ssim: Vec<bool> = rows.iter().map(|r| r.pareto_ssim).collect();
        assert_eq!(ssim, [true, true, false, true, false]);
    }

    #[test]
    fn equal_points_are_both_on_the_front() {
        let mut rows = vec![row(5.0, 30.0, 0.9), row(5.0, 30.0, 0.9)];
        mark_pareto_fronts(&mut rows);
        assert!(rows.iter().all(|r| r.pareto_psnr && r.pareto_ssim));
    }

    #[test]
    fn answer_respects_its_budget() {
        let r = report(vec![
            row(5.0, 28.0, 0.90),
            row(7.0, 35.0, 0.93),
            row(6.0, 31.0, 0.99),
        ]);
        let pick = |budget| r.choose(budget, true).result;
        assert_eq!(pick(Budget::Psnr(30.0)), Some(2));
        assert_eq!(pick(Budget::Psnr(33.0)), Some(1));
        assert_eq!(pick(Budget::Ssim(0.95)), Some(2));
        assert_eq!(pick(Budget::Psnr(20.0)), Some(0));
        // The default budget is SSIM ≥ 0.95.
        assert_eq!(r.choose(Budget::DEFAULT, false).result, Some(2));
        let none = r.choose(Budget::Psnr(50.0), true);
        assert_eq!(none.result, None);
        assert!(none.none_within_budget);
        assert!(none.reason.contains("none of the 3"), "{}", none.reason);
        // Closest without the budget: the least error of those faster.
        assert_eq!(none.closest, Some(1));
    }

    #[test]
    fn answer_never_recommends_a_slowdown() {
        // Slower than the original: no answer, though within the budget.
        let r = report(vec![row(12.0, 35.0, 0.99)]);
        let choice = r.choose(Budget::Psnr(30.0), true);
        assert_eq!(choice.result, None);
        assert!(!choice.none_within_budget);
        assert_eq!(choice.closest, Some(0));
        assert!(
            choice.reason.contains("keep the original"),
            "{}",
            choice.reason
        );
        // Faster by its median, but its interval reaches below 1×: noise.
        let mut noisy = row(9.0, 35.0, 0.99);
        noisy.speedup_ci = [0.93, 1.25];
        let choice = report(vec![noisy]).choose(Budget::Psnr(30.0), true);
        assert_eq!(choice.result, None);
        assert!(
            choice.reason.contains("beyond this run's noise"),
            "{}",
            choice.reason
        );
    }

    /// A slow configuration named as closest says how much slower it is,
    /// and the faster one over the budget is offered beside it with how
    /// far it falls short: never a bare 0.17×.
    #[test]
    fn closest_says_how_far_it_is_from_an_answer() {
        // Reference 10 ms: 58.8 ms is 0.17×, within SSIM ≥ 0.95; 4 ms is
        // 2.5×, at SSIM 0.87, as accurate as 5 ms and faster.
        let r = report(vec![
            row(58.8, 45.0, 0.99),
            row(5.0, 36.6, 0.87),
            row(4.0, 36.6, 0.87),
        ]);
        let choice = r.choose(Budget::DEFAULT, false);
        assert_eq!(choice.result, None);
        assert_eq!(choice.closest, Some(0));
        assert!(
            choice.reason.contains("5.9× slower than the original"),
            "{}",
            choice.reason
        );
        assert!(
            choice
                .reason
                .contains("Faster but over the budget: node n4 ")
                && choice.reason.contains("SSIM 0.0800 short of SSIM ≥ 0.95"),
            "{}",
            choice.reason
        );
        assert!(choice.reason.contains("1 configuration is within"));
    }

    #[test]
    fn a_winner_the_confirmatory_run_does_not_repeat_is_not_recommended() {
        let r = report(vec![row(5.0, 35.0, 0.99)]);
        let confirmation = |lo: f64| Confirmation {
            frames: 8,
            reference_ms: 10.0,
            time_ms: 9.0,
            speedup: 1.1,
            speedup_ci: [lo, 1.3],
        };
        let mut kept = r.choose(Budget::Psnr(30.0), true);
        kept.confirm(confirmation(1.02));
        assert_eq!(kept.result, Some(0));
        assert!(kept.reason.contains("measured again"), "{}", kept.reason);
        let mut dropped = r.choose(Budget::Psnr(30.0), true);
        dropped.confirm(confirmation(0.95));
        assert_eq!(dropped.result, None);
        assert_eq!(dropped.closest, Some(0));
        assert!(dropped.confirmation.is_some());
        assert!(
            dropped.reason.contains("keep the original"),
            "{}",
            dropped.reason
        );
    }

    #[test]
    fn budgets_parse() {
        assert_eq!("psnr:30".parse::<Budget>(), Ok(Budget::Psnr(30.0)));
        assert_eq!("SSIM=0.95".parse::<Budget>(), Ok(Budget::Ssim(0.95)));
        assert!("ssim:2".parse::<Budget>().is_err());
        assert!("psnr:NaN".parse::<Budget>().is_err());
        assert!("mse:1".parse::<Budget>().is_err());
        assert!("30".parse::<Budget>().is_err());
    }
}
