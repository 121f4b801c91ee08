//! The deposits (docs/design.md "Emitters and deposits"): where a frame's photon landings are kept until the eye
//! view reads them. A landing tries them in [`DEPOSITS`]' order (glsl/common/deposit.glsl `deposit_landing`), and
//! what none holds is `unseen` in the energy account. Each declares what it needs of the frame around the
//! photons ([`Declares`]), and [`order`] places the frame's steps from those declarations, so that a new deposit
//! is its own files (its GLSL project, footprint, splat and lookup; its store in src/targets.rs) and a line here.

use crate::shaders::consts::{ACC_CAUSTIC, ACC_EYE};

/// A kind of deposit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Deposit {
    /// The papers' light-space caustic map, one per light view: one receiver per texel, where the light's
    /// straight rays land (glsl/common/deposit_light_map.glsl). The fast path.
    LightMap,
    /// The eye deposit: flux per eye sample, where the camera sees a landing the light maps cannot hold
    /// (glsl/common/deposit_eye.glsl).
    Eye,
}

/// The deposits in the order a landing tries them: the first that holds it takes it.
pub(crate) const DEPOSITS: [Deposit; 2] = [Deposit::LightMap, Deposit::Eye];

/// Whether a deposit's store is one per light view or one for the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scope {
    /// Each light view has its own, cleared by its photons' first batch and resolved after its last.
    Emitter,
    /// One for every light view of the frame: cleared once, before the first light's photons.
    Frame,
}

/// What a deposit needs of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Declares {
    pub scope: Scope,
    /// It projects landings into the receivers' g-buffer from the eye, which is then drawn before the lights'
    /// photons (else step 7 draws it).
    pub eye_gbuffer_first: bool,
    /// It depends on the camera: a frame for another eye view reuses the light views' passes only where nothing
    /// landed in it (src/renderer/keys.rs).
    pub follows_camera: bool,
    /// Its term of the energy account: the flux it holds (`ACC_EYE` is a part of `ACC_CAUSTIC`).
    pub account: u32,
}

impl Deposit {
    pub fn declares(self) -> Declares {
        match self {
            Deposit::LightMap => Declares {
                scope: Scope::Emitter,
                eye_gbuffer_first: false,
                follows_camera: false,
                account: ACC_CAUSTIC,
            },
            Deposit::Eye => {
                Declares { scope: Scope::Frame, eye_gbuffer_first: true, follows_camera: true, account: ACC_EYE }
            }
        }
    }
}

/// A step of the frame around the light views' passes, in the order [`order`] gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// Clear a frame-scoped deposit's store.
    Clear(Deposit),
    /// Draw the receivers' eye g-buffer (before the photons, for a deposit that projects into it).
    EyeGbuffer,
    /// Steps 1 to 6 for every light view and color channel.
    LightViews,
    /// Step 7: the eye view, drawing the receivers' eye g-buffer unless an earlier step did.
    EyeView { gbuffer: bool },
}

/// The steps of a frame whose active deposits are `active` (a subset of [`DEPOSITS`]): a frame-scoped store is
/// cleared first when `clear` (a frame that traces for a new eye view), and the eye's g-buffer is drawn before the
/// photons when a deposit projects into it and the frame records its light views and eye view (`lights`,
/// `eye`: not reused).
pub(crate) fn order(active: &[Deposit], clear: bool, lights: bool, eye: bool) -> Vec<Step> {
    let mut steps = Vec::new();
    if clear {
        steps.extend(active.iter().filter(|d| d.declares().scope == Scope::Frame).map(|&d| Step::Clear(d)));
    }
    let first = lights && eye && active.iter().any(|d| d.declares().eye_gbuffer_first);
    if first {
        steps.push(Step::EyeGbuffer);
    }
    steps.push(Step::LightViews);
    if eye {
        steps.push(Step::EyeView { gbuffer: !first });
    }
    steps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The eye deposit's g-buffer comes before the photons; without it, the eye view draws it after them. Its store
    /// is cleared first only for a new eye view; the light maps' stores are their views' own.
    #[test]
    fn the_frame_orders_its_steps_from_the_deposits() {
        use Step::*;
        let both = [Deposit::LightMap, Deposit::Eye];
        assert_eq!(
            order(&both, true, true, true),
            [Clear(Deposit::Eye), EyeGbuffer, LightViews, EyeView { gbuffer: false }]
        );
        assert_eq!(order(&both, false, true, true), [EyeGbuffer, LightViews, EyeView { gbuffer: false }]);
        assert_eq!(order(&[Deposit::LightMap], true, true, true), [LightViews, EyeView { gbuffer: true }]);
        // Maps reused (the eye deposit's flux is kept), or the eye view reused: nothing to draw early.
        assert_eq!(order(&both, false, false, true), [LightViews, EyeView { gbuffer: true }]);
        assert_eq!(order(&both, false, true, false), [LightViews]);
        assert_eq!(DEPOSITS.iter().filter(|d| d.declares().follows_camera).count(), 1);
    }
}
