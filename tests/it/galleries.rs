//! Committed galleries (`figures/<profile>/`) against what their profiles would build now:
//! compared by instance keys (content hashes of the jobs), not pixels.

use std::collections::BTreeSet;

use wearcoef::config::Pipeline;
use wearcoef::pipeline::gallery::{expected, Provenance, PROVENANCE};
use wearcoef::pipeline::plan::Plan;

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
        assert_eq!(
            keys_only(committed.clone()),
            now,
            "figures/{profile} is stale: `make figures PROFILE={profile}` and commit it"
        );
        // The gallery holds exactly the files its figures wrote, and all of them.
        let listed: BTreeSet<String> = committed
            .figures
            .iter()
            .flat_map(|f| f.files.iter().cloned())
            .collect();
        let present: BTreeSet<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n != PROVENANCE && n != "index.html" && !n.starts_with('.'))
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
