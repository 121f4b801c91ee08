//! `caustics temporal` end to end, small: two light positions, level 1, a small reference. The table has one
//! row per method with finite error and flicker, and validation stays silent.

mod common;
use common::*;

#[test]
fn temporal_reports_error_and_flicker() {
    let dir = out_dir("temporal");
    let (json, md) = (dir.join("t.json"), dir.join("t.md"));
    let cache = dir.join("cache");
    let o = caustics_env(
        &[
            "temporal",
            "--frames",
            "3",
            "--level",
            "1",
            "--size",
            "64x64",
            "--map-res",
            "256",
            "--reference-photons",
            "100000",
            "--json",
            json.to_str().unwrap(),
            "--markdown",
            md.to_str().unwrap(),
        ],
        &[("CAUSTICS_CACHE_DIR", cache.to_str().unwrap())],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let s = read_json(&json);
    let rows = s["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for r in rows {
        for k in ["mean_rel_l1", "flicker", "frame_change"] {
            let v = r[k].as_f64().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{k} = {v}: {r}");
        }
        // Against a two-refraction reference, the two-interface model at level 1 is within 30% everywhere.
        assert!(r["mean_rel_l1"].as_f64().unwrap() < 0.3, "{r}");
    }
    assert!(std::fs::read_to_string(&md).unwrap().contains("| max-error | 1 |"));
    // The references were cached (one per light position) and are reused.
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 3);
}
