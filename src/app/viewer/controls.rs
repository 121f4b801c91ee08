//! The viewer's controls: one table that drives both the key handling and the help that `H` prints (and that
//! docs/viewer.md copies; tests/docs.rs checks the copy).

use winit::keyboard::{Key, NamedKey};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    LightLeft,
    LightRight,
    LightAway,
    LightNear,
    LightUp,
    LightDown,
    IorDown,
    IorUp,
    LevelDown,
    LevelUp,
    ResolutionDown,
    ResolutionUp,
    Dense,
    AdaptiveMaxLevel,
    AdaptiveMaxError,
    AdaptiveFluxError,
    Transport,
    Refine,
    Animate,
    PlayScene,
    NextAnimation,
    Screenshot,
    Profile,
    Trace,
    Reset,
    Overlay,
    Help,
    Quit,
}

impl Action {
    /// Actions that make sense to repeat while a key is held.
    pub fn repeats(self) -> bool {
        use Action::*;
        matches!(self, LightLeft | LightRight | LightAway | LightNear | LightUp | LightDown | IorDown | IorUp)
    }
}

/// One row of the help: what to press, what it does, and the key names (see [`key_name`]) bound to actions.
pub struct Control {
    pub input: &'static str,
    pub help: &'static str,
    pub keys: &'static [(&'static str, Action)],
}

pub const CONTROLS: &[Control] = &[
    Control { input: "left drag", help: "orbit the camera around its target", keys: &[] },
    Control { input: "left click", help: "drop into the simulated water under the cursor", keys: &[] },
    Control { input: "scroll", help: "zoom", keys: &[] },
    Control { input: "right drag", help: "move the light in the horizontal plane (relative to the view)", keys: &[] },
    Control {
        input: "Shift + left drag",
        help: "move the glass object under the cursor in the horizontal plane (relative to the view)",
        keys: &[],
    },
    Control {
        input: "← → ↑ ↓",
        help: "move the light left, right, away, closer (relative to the view)",
        keys: &[
            ("ArrowLeft", Action::LightLeft),
            ("ArrowRight", Action::LightRight),
            ("ArrowUp", Action::LightAway),
            ("ArrowDown", Action::LightNear),
        ],
    },
    Control {
        input: "PgUp PgDn",
        help: "move the light up, down",
        keys: &[("PageUp", Action::LightUp), ("PageDown", Action::LightDown)],
    },
    Control {
        input: "[ ]",
        help: "index of refraction of every dielectric −/+ 0.05",
        keys: &[("[", Action::IorDown), ("]", Action::IorUp)],
    },
    Control {
        input: "- =",
        help: "maximal traversal level (dense: grid level) −/+ 1",
        keys: &[("-", Action::LevelDown), ("=", Action::LevelUp), ("+", Action::LevelUp)],
    },
    Control {
        input: ", .",
        help: "caustic-map resolution ÷2 / ×2",
        keys: &[(",", Action::ResolutionDown), (".", Action::ResolutionUp)],
    },
    Control {
        input: "1 2 3 4",
        help: "method: dense / adaptive max-level / adaptive max-error / adaptive flux-error (the default)",
        keys: &[
            ("1", Action::Dense),
            ("2", Action::AdaptiveMaxLevel),
            ("3", Action::AdaptiveMaxError),
            ("4", Action::AdaptiveFluxError),
        ],
    },
    Control {
        input: "X",
        help: "transport: exact (every glass path) / two-interface (the papers' model, cheaper)",
        keys: &[("x", Action::Transport)],
    },
    Control {
        input: "C",
        help: "flux-error refinement: light-driven (the caustic map's error) / camera-driven (the image's: photons \
               where the camera looks, traced again when it moves)",
        keys: &[("c", Action::Refine)],
    },
    Control {
        input: "Space",
        help: "animate the light (orbit the vertical axis through its target) / pause",
        keys: &[("Space", Action::Animate)],
    },
    Control {
        input: "A",
        help: "play / pause the scene's animation (its keyframed objects; the light's is Space)",
        keys: &[("a", Action::PlayScene)],
    },
    Control {
        input: "N",
        help: "glTF: play the next animation alone (all of them together after the last)",
        keys: &[("n", Action::NextAnimation)],
    },
    Control { input: "S", help: "save a screenshot (PNG, name printed)", keys: &[("s", Action::Screenshot)] },
    Control {
        input: "P",
        help: "print per-stage GPU ms (mean, median, min, max over the last 120 frames)",
        keys: &[("p", Action::Profile)],
    },
    Control {
        input: "T",
        help: "write a Chrome trace of the last 120 frames (name printed)",
        keys: &[("t", Action::Trace)],
    },
    Control { input: "R", help: "reset the camera, the light and the glass", keys: &[("r", Action::Reset)] },
    Control {
        input: "F1",
        help: "show or hide the overlay: GPU ms per stage, the frame's photons and energy, buttons for these keys",
        keys: &[("F1", Action::Overlay)],
    },
    Control { input: "H", help: "print these controls", keys: &[("h", Action::Help)] },
    Control { input: "Esc Q", help: "quit", keys: &[("Escape", Action::Quit), ("q", Action::Quit)] },
];

/// The table's name for a key: named keys by their winit name (`ArrowLeft`, `PageUp`, `Space`), characters in
/// lower case.
pub fn key_name(key: &Key) -> Option<String> {
    match key {
        Key::Named(NamedKey::Space) => Some("Space".into()),
        Key::Named(n) => Some(format!("{n:?}")),
        Key::Character(c) if c.as_str() == " " => Some("Space".into()),
        Key::Character(c) => Some(c.to_lowercase()),
        _ => None,
    }
}

pub fn action_for(key: &Key) -> Option<Action> {
    let name = key_name(key)?;
    CONTROLS.iter().flat_map(|c| c.keys.iter()).find(|(k, _)| *k == name).map(|(_, a)| *a)
}

/// The controls as a plain-text table.
pub fn help_text() -> String {
    let width = CONTROLS.iter().map(|c| c.input.chars().count()).max().unwrap_or(0);
    let mut out = String::from("caustics view controls:\n");
    for c in CONTROLS {
        let pad = width - c.input.chars().count();
        out.push_str(&format!("  {}{}   {}\n", c.input, " ".repeat(pad), c.help));
    }
    out
}

/// The controls as a Markdown table (`caustics view --print-controls`; docs/viewer.md holds a copy).
pub fn help_markdown() -> String {
    let mut out = String::from("| Input | Action |\n|---|---|\n");
    for c in CONTROLS {
        let input = if c.keys.is_empty() {
            c.input.to_string()
        } else {
            c.input.split(' ').map(|k| format!("`{k}`")).collect::<Vec<_>>().join(" ")
        };
        out.push_str(&format!("| {input} | {} |\n", c.help));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_bound_once() {
        let mut seen = std::collections::HashSet::new();
        for (k, _) in CONTROLS.iter().flat_map(|c| c.keys.iter()) {
            assert!(seen.insert(*k), "key {k} bound twice");
        }
    }

    #[test]
    fn keys_resolve() {
        assert_eq!(action_for(&Key::Character("S".into())), Some(Action::Screenshot));
        assert_eq!(action_for(&Key::Named(NamedKey::Space)), Some(Action::Animate));
        assert_eq!(action_for(&Key::Character(" ".into())), Some(Action::Animate));
        assert_eq!(action_for(&Key::Named(NamedKey::ArrowLeft)), Some(Action::LightLeft));
        assert_eq!(action_for(&Key::Named(NamedKey::Escape)), Some(Action::Quit));
        assert_eq!(action_for(&Key::Character("x".into())), Some(Action::Transport));
        assert_eq!(action_for(&Key::Character("C".into())), Some(Action::Refine));
        assert_eq!(action_for(&Key::Character("z".into())), None);
        assert!(help_text().contains("screenshot"));
    }
}
