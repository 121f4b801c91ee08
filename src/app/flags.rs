//! The CLI's names for the library's settings. The library's [`Error::Setting`] names a field as its types do
//! (`Quality::level`), for a program that sets it in code; the CLI says the flag its user typed (`--level`).

use caustics::Error;

/// (the library's field, the CLI's flag). Every field the library names in an [`Error::Setting`] is here (a test
/// holds it), and every flag is an option of `render` or `reference`.
pub const FLAGS: &[(&str, &str)] = &[
    ("Quality::level", "--level"),
    ("Quality::caustic_res", "--caustic-res"),
    ("Quality::photon_budget_mib", "--photon-budget"),
    ("Quality::target_error", "--target-error"),
    ("Quality::exposure_ev", "--exposure"),
    ("Quality::aa", "--aa"),
    ("Quality::sky", "--sky"),
    ("Quality::eye_depth", "--eye-depth"),
    ("Quality::transport", "--transport"),
    ("Tuning::gbuffer_res", "--gbuffer-res"),
    ("Tuning::error_bound", "--error-bound"),
    ("Tuning::tau", "--tau"),
    ("Tuning::flux_threshold", "--flux-threshold"),
    ("Tuning::weak_branches", "--weak-branches"),
    ("Tuning::weak_block", "--weak-block"),
    ("Tuning::traverse_wg", "--traverse-wg"),
    ("Tuning::debug_photons", "--debug-photons"),
    ("Tuning::batch_slots", "--batch-slots"),
    ("Tuning::bvh_layout", "--bvh-layout"),
    ("RefParams::photons", "--photons"),
    ("RefParams::width", "--size"),
    ("RefParams::time", "--time"),
    ("RefParams::camera", "--camera"),
];

/// `Scene::camera`'s error for `--camera NAME`.
pub fn camera_error(name: Option<&str>, e: String) -> Error {
    match name {
        Some(n) => Error::BadInput(format!("--camera {n}: {e}")),
        None => Error::BadInput(e),
    }
}

/// An error as the CLI prints it: a setting by its flag, anything else as the library words it.
pub fn message(e: &Error) -> String {
    if let Error::Setting { field, value, rule } = e {
        if let Some((_, flag)) = FLAGS.iter().find(|(f, _)| f == field) {
            return format!("{flag} {value}: {rule}");
        }
    }
    e.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_setting_is_printed_by_its_flag_and_the_library_names_its_field() {
        let e = Error::setting("Quality::level", 13, "must be at most 12");
        assert_eq!(e.to_string(), "Quality::level = 13: must be at most 12");
        assert_eq!(message(&e), "--level 13: must be at most 12");
        assert_eq!(e.exit_code(), 2);
    }

    /// Every field the library's sources name in a string literal (`"Quality::level"`: what `Error::setting` and
    /// `Settings::validate` take) has a flag here.
    #[test]
    fn every_field_the_library_names_has_a_flag() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let is_field = |s: &str| {
            s.split_once("::").is_some_and(|(ty, f)| {
                ["Quality", "Tuning", "RefParams"].contains(&ty)
                    && !f.is_empty()
                    && f.chars().all(|c| c.is_ascii_lowercase() || c == '_')
            })
        };
        let mut named = Vec::new();
        let mut dirs = vec![root.clone()];
        while let Some(d) = dirs.pop() {
            for entry in std::fs::read_dir(&d).unwrap() {
                let p = entry.unwrap().path();
                if p.is_dir() {
                    if p != root.join("app") {
                        dirs.push(p);
                    }
                } else if p.extension().is_some_and(|x| x == "rs") {
                    let text = std::fs::read_to_string(&p).unwrap();
                    for literal in text.split('"').skip(1).step_by(2).filter(|l| is_field(l)) {
                        named.push((p.display().to_string(), literal.to_string()));
                    }
                }
            }
        }
        assert!(named.len() >= 25, "{named:?}");
        for (file, field) in &named {
            assert!(FLAGS.iter().any(|(f, _)| f == field), "{file}: `{field}` has no flag in src/app/flags.rs");
        }
    }
}
