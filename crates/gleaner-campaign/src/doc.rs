//! A campaign's summary as the versioned document `gleaner.campaign`
//! ([`gleaner_wire::docs::CampaignDoc`], served by `POST /api/v1/simulate`).

use gleaner_app::format_rfc3339;
use gleaner_wire::docs::{CampaignDoc, FlightSummaryDoc, IntervalDoc, StrategySummaryDoc};
use gleaner_wire::{CAMPAIGN_FORMAT, VERSION};

use crate::campaign::{CampaignSummary, Interval};

/// A mean with its interval; non-finite numbers become `null`.
fn interval(i: &Interval) -> IntervalDoc {
    let finite = |x: f64| x.is_finite().then_some(x);
    IntervalDoc {
        mean: finite(i.mean),
        low: finite(i.low),
        high: finite(i.high),
        n: i.n,
    }
}

/// Per strategy, how a campaign's sorties flew in its weather (`CampaignDoc::flights`).
pub fn flights(f: &[crate::campaign::FlightSummary]) -> Vec<FlightSummaryDoc> {
    f.iter()
        .map(|f| FlightSummaryDoc {
            strategy: f.strategy.name().into(),
            missions: f.missions,
            mean_forecast_mps: f.mean_forecast_mps,
            replanned: f.replanned,
            cells_dropped: f.cells_dropped,
            readings: f.readings,
            readings_calm_days: f.readings_calm_days,
            calm_days: f.calm_days,
            over_budget: f.over_budget,
            max_excess_j: f.max_excess_j.is_finite().then_some(f.max_excess_j),
        })
        .collect()
}

/// A campaign's summary: per strategy and budget, every metric with its interval (without
/// flights: see [`flights`]).
pub fn campaign_doc(c: &CampaignSummary) -> CampaignDoc {
    CampaignDoc {
        format: CAMPAIGN_FORMAT.into(),
        version: VERSION,
        label: c.label.clone(),
        modality: c.modality.clone(),
        period_s: c.period_s,
        history_until: format_rfc3339(c.history_until),
        missions: c.schedule.len(),
        first_mission: c.schedule.first().map(|&t| format_rfc3339(t)),
        last_mission: c.schedule.last().map(|&t| format_rfc3339(t)),
        events: c.events,
        reference: c.reference.name().into(),
        strategies: c
            .summaries
            .iter()
            .map(|s| StrategySummaryDoc {
                strategy: s.strategy.name().into(),
                budget: s.budget,
                runs: s.runs,
                metrics: s
                    .metrics
                    .iter()
                    .map(|(name, i)| (name.to_string(), interval(i)))
                    .collect(),
                events_caught: s.events_caught.0,
                events: s.events_caught.1,
                delay_days: interval(&s.delay_days),
                rmse_vs_reference: s.rmse_vs_reference.as_ref().map(interval),
                delay_vs_reference: s.delay_vs_reference.as_ref().map(interval),
            })
            .collect(),
        flights: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use gleaner_wire::CAMPAIGN_FORMAT;
    use gleaner_wire::docs::CampaignDoc;

    use crate::campaign::{CampaignSummary, Interval, Strategy, Summary};

    #[test]
    fn campaign_document() {
        let i = |mean: f64, low: f64, high: f64, n: usize| Interval { mean, low, high, n };
        let summary = |strategy, rmse: Interval, vs: Option<Interval>| Summary {
            strategy,
            budget: 1.0,
            runs: 1,
            metrics: vec![
                ("rmse_kriged", rmse),
                ("energy_kj", i(65.7, 65.1, 66.2, 5)),
                // One block only: a mean without an interval.
                ("classifier_accuracy", i(0.95, f64::NAN, f64::NAN, 1)),
            ],
            events_caught: (3, 4),
            delay_days: i(1.5, 0.5, 2.5, 3),
            rmse_vs_reference: vs,
            delay_vs_reference: vs.map(|_| i(0.25, -0.5, 1.0, 3)),
        };
        let c = CampaignSummary {
            label: "north-field".into(),
            modality: "vw@30cm".into(),
            period_s: 86_400,
            history_until: 1_400_000_000 - 1_400_000_000 % 86_400,
            schedule: vec![1_399_939_200, 1_400_025_600],
            events: 4,
            reference: Strategy::Gleaner,
            summaries: vec![
                summary(Strategy::Gleaner, i(0.004, 0.003, 0.005, 5), None),
                summary(
                    Strategy::RoundRobin,
                    i(0.005, 0.004, 0.006, 5),
                    Some(i(0.001, -0.0002, 0.0022, 5)),
                ),
            ],
        };
        let doc = super::campaign_doc(&c);
        assert_eq!(doc.format, CAMPAIGN_FORMAT);
        assert_eq!(doc.missions, 2);
        assert_eq!(doc.reference, "gleaner");
        assert_eq!(doc.strategies[1].strategy, "round-robin");
        assert_eq!(
            (doc.strategies[0].events_caught, doc.strategies[0].events),
            (3, 4)
        );
        // Undefined ends are null, not NaN (JSON has none).
        let acc = &doc.strategies[0].metrics["classifier_accuracy"];
        assert_eq!((acc.mean, acc.low, acc.high), (Some(0.95), None, None));
        assert!(doc.strategies[0].rmse_vs_reference.is_none());
        let text = serde_json::to_string_pretty(&doc).unwrap();
        assert!(!text.contains("NaN"));
        let back: CampaignDoc = serde_json::from_str(&text).unwrap();
        assert_eq!(back, doc);
        insta::assert_snapshot!("campaign.json", text);
    }
}
