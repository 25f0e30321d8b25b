//! Committed galleries (`figures/<profile>/`) against what their profiles would build now:
//! compared by instance keys (content hashes of the jobs), not pixels.
//!
//! A gallery whose redraw needs a campaign longer than a session (the paper's sizes) may lag
//! the program only if it says so: `REDRAW.md` beside it names what drew it, why it is no
//! longer current, and the command that redraws it. A current gallery has no such note.

use std::collections::BTreeSet;

use wearcoef::config::Pipeline;
use wearcoef::pipeline::gallery::{expected, Provenance, PROVENANCE};
use wearcoef::pipeline::plan::Plan;

/// The note a gallery that lags its profile carries.
const REDRAW_NOTE: &str = "REDRAW.md";

/// A stage and the studies of one instance a figure is drawn from.
type Source = (String, Vec<String>);

/// Each figure with the stages and studies it is drawn from, keys aside: what a lagging
/// gallery still shares with its profile now.
fn figures_and_sources(p: &Provenance) -> Vec<(String, Vec<Source>)> {
    let mut v: Vec<_> = p
        .figures
        .iter()
        .map(|f| {
            let mut from: Vec<_> = f
                .drawn_from
                .iter()
                .map(|d| (d.stage.clone(), d.studies.clone()))
                .collect();
            from.sort();
            (f.figure.clone(), from)
        })
        .collect();
    v.sort();
    v
}

/// Without the files each figure wrote (the plan does not know them).
fn keys_only(mut p: Provenance) -> Provenance {
    for f in &mut p.figures {
        f.files.clear();
    }
    p
}

#[test]
fn committed_galleries_match_what_their_profiles_would_draw() {
    let repo = &crate::repo_root();
    let pipeline = Pipeline::load(&repo.join("pipeline.yaml")).unwrap();
    let mut checked = 0;
    for entry in std::fs::read_dir(repo.join("figures")).unwrap() {
        let dir = entry.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let record = dir.join(PROVENANCE);
        assert!(
            record.is_file(),
            "{} has no {PROVENANCE}: a gallery must say what it was drawn from \
             (`make figures PROFILE=<its profile>` writes it)",
            dir.display()
        );
        let committed: Provenance =
            serde_json::from_str(&std::fs::read_to_string(&record).unwrap()).unwrap();
        let profile = dir.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(committed.profile, profile, "{}", record.display());
        let plan = Plan::build(&pipeline, "pipeline.yaml", &profile, &[]).unwrap();
        let now = expected(&plan.instances, &profile);
        let note = dir.join(REDRAW_NOTE);
        if keys_only(committed.clone()) == now {
            assert!(
                !note.exists(),
                "figures/{profile} is current: remove its {REDRAW_NOTE}"
            );
        } else {
            let text = std::fs::read_to_string(&note).unwrap_or_else(|_| {
                panic!(
                    "figures/{profile} is stale: `make figures PROFILE={profile}` and commit \
                     it (or, for a campaign longer than a session, say so in {REDRAW_NOTE})"
                )
            });
            let command = format!("scripts/campaign.sh start {profile}");
            assert!(
                text.contains(&command) && text.contains("Drawn by") && text.contains("Stale"),
                "figures/{profile}/{REDRAW_NOTE} must say what drew it ('Drawn by'), what is \
                 no longer current ('Stale') and the command that redraws it ({command})"
            );
            // It lags in what is computed from the data, not in what it draws.
            assert_eq!(
                figures_and_sources(&committed),
                figures_and_sources(&now),
                "figures/{profile}: its figures are not those its profile declares now"
            );
        }
        // The gallery holds exactly the files its figures wrote, and all of them.
        let listed: BTreeSet<String> = committed
            .figures
            .iter()
            .flat_map(|f| f.files.iter().cloned())
            .collect();
        let present: BTreeSet<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| {
                n != PROVENANCE && n != "index.html" && n != REDRAW_NOTE && !n.starts_with('.')
            })
            .collect();
        assert_eq!(
            present, listed,
            "figures/{profile}: files against its record"
        );
        assert!(
            committed.figures.iter().all(|f| !f.files.is_empty()),
            "figures/{profile}: a declared figure drew nothing"
        );
        // Its report, with the numbers behind the figures it holds.
        let page = std::fs::read_to_string(dir.join("index.html"))
            .unwrap_or_else(|e| panic!("figures/{profile}/index.html: {e}"));
        for (file, section) in [
            ("fig2e.png", "Area–load slope"),
            ("fig4b.png", "Plateau of K"),
            ("fig3.png", "Exponents α̂ at the loads drawn"),
        ] {
            if listed.contains(file) {
                assert!(
                    page.contains(section),
                    "figures/{profile}/index.html lacks '{section}'"
                );
            }
        }
        checked += 1;
    }
    assert!(checked >= 1, "no committed gallery");
}
