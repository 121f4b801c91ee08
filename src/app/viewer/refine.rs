//! The viewer's refinement policy, pure: the level a frame renders at, whether it is a preview and at which scale
//! it is drawn, and how the interactive level and the preview scale follow what frames cost.
//!
//! Progressive refinement: an interactive level while the light or the glass changes, then one level more per
//! frame up to the chosen one (each frame complete and flux-correct at its level). The eye view's detail waits for
//! the view to hold still: a frame in which the camera, the light or the glass moved, or that is still refining,
//! is a preview (one eye sample per pixel, maybe at a lower resolution; glass traced as in a still under exact
//! transport).

/// GPU time the eye view of a preview frame (eye and composite passes) aims at: above it, previews are drawn at a
/// lower resolution (dynamic resolution, `--preview-scale auto`).
pub const PREVIEW_EYE_MS: f64 = 30.0;
/// The coarsest automatic preview: 1/MAX_PREVIEW_SCALE of the window's resolution per side.
pub const MAX_PREVIEW_SCALE: u32 = 4;

/// The level of the next frame: the chosen one without progressive refinement; the interactive level (at most the
/// chosen one) while interacting; else one level above the last frame's, from the interactive level up to the
/// chosen one.
pub fn frame_level(progressive: bool, interacting: bool, chosen: u32, interactive: u32, shown: u32) -> u32 {
    if !progressive {
        chosen
    } else if interacting {
        chosen.min(interactive)
    } else {
        chosen.min(shown.saturating_add(1)).max(chosen.min(interactive))
    }
}

/// Whether the frame is a preview: with progressive refinement, one in which the camera moved, the user
/// interacts, or that is still below the chosen level. Only the last of the frames refining toward the chosen
/// level pays for the full eye view.
pub fn is_preview(progressive: bool, moved: bool, interacting: bool, level: u32, chosen: u32) -> bool {
    progressive && (moved || interacting || level < chosen)
}

/// The photon sets the next frame's caustic maps may average ([`caustics::Renderer::set_accumulation`]): a view
/// still at the chosen level converges, each frame adding a set, up to `accumulate`; a moving or refining one keeps
/// (and reuses) the average it has until a change of what the maps depend on starts a new one.
pub fn photon_sets(moving: bool, level: u32, chosen: u32, accumulate: u32) -> u32 {
    if moving || level < chosen {
        1
    } else {
        accumulate
    }
}

/// The scale a frame is drawn at (the copy to the swapchain image scales it up): a preview's, except for a
/// screenshot's frame, drawn at full resolution.
pub fn draw_scale(preview: bool, capture: bool, preview_scale: u32) -> u32 {
    if preview && !capture {
        preview_scale
    } else {
        1
    }
}

/// The preview scale after a preview drawn at `scale` whose eye view took `eye_ms`: coarser as soon as it costs
/// more than [`PREVIEW_EYE_MS`]; finer when the next finer scale would still fit with a margin if all of the cost
/// scaled with the pixels (part of it, the vertices, does not, so the real cost there is lower).
pub fn adapt_preview_scale(scale: u32, eye_ms: f64) -> u32 {
    if eye_ms > PREVIEW_EYE_MS && scale < MAX_PREVIEW_SCALE {
        scale + 1
    } else if scale > 1
        && eye_ms * ((scale * scale) as f64 / ((scale - 1) * (scale - 1)) as f64) <= 0.8 * PREVIEW_EYE_MS
    {
        scale - 1
    } else {
        scale
    }
}

/// The interactive level after an interactive frame at `interactive` (at most `chosen`) that took `gpu_ms`: kept
/// near `target_ms`, a level costing up to 4 times the one below it.
pub fn adapt_interactive_level(interactive: u32, chosen: u32, gpu_ms: f64, target_ms: f64) -> u32 {
    if gpu_ms > 1.5 * target_ms && interactive > 0 {
        interactive - 1
    } else if gpu_ms < 0.3 * target_ms && interactive < chosen {
        interactive + 1
    } else {
        interactive
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_view_climbs_one_level_a_frame_from_the_interactive_level_to_the_chosen_one() {
        let (chosen, interactive) = (5, 2);
        let mut shown = 0;
        let mut levels = Vec::new();
        for _ in 0..6 {
            shown = frame_level(true, false, chosen, interactive, shown);
            levels.push(shown);
        }
        assert_eq!(levels, [2, 3, 4, 5, 5, 5]);
        // Interaction drops to the interactive level; without refinement every frame is at the chosen one.
        assert_eq!(frame_level(true, true, chosen, interactive, 5), 2);
        assert_eq!(frame_level(false, true, chosen, interactive, 0), 5);
        // An interactive level above the chosen one is the chosen one.
        assert_eq!(frame_level(true, true, 1, 3, 0), 1);
    }

    #[test]
    fn only_the_still_frame_at_the_chosen_level_is_full() {
        assert!(is_preview(true, false, false, 4, 5));
        assert!(is_preview(true, true, false, 5, 5));
        assert!(is_preview(true, false, true, 5, 5));
        assert!(!is_preview(true, false, false, 5, 5));
        assert!(!is_preview(false, true, true, 0, 5));
        assert_eq!(draw_scale(true, false, 3), 3);
        assert_eq!(draw_scale(true, true, 3), 1);
        assert_eq!(draw_scale(false, false, 3), 1);
    }

    #[test]
    fn the_preview_scale_and_interactive_level_follow_the_cost() {
        assert_eq!(adapt_preview_scale(1, 31.0), 2);
        assert_eq!(adapt_preview_scale(MAX_PREVIEW_SCALE, 100.0), MAX_PREVIEW_SCALE);
        // At scale 2 the full resolution would cost 4x: 5 ms fits (20 <= 24), 7 ms does not (28).
        assert_eq!(adapt_preview_scale(2, 5.0), 1);
        assert_eq!(adapt_preview_scale(2, 7.0), 2);
        assert_eq!(adapt_interactive_level(3, 5, 200.0, 100.0), 2);
        assert_eq!(adapt_interactive_level(3, 5, 20.0, 100.0), 4);
        assert_eq!(adapt_interactive_level(5, 5, 20.0, 100.0), 5);
        assert_eq!(adapt_interactive_level(0, 5, 900.0, 100.0), 0);
        assert_eq!(adapt_interactive_level(3, 5, 100.0, 100.0), 3);
    }
}
