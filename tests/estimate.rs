//! Frame estimates hold: `Renderer::estimate` (probe frames at lower levels and a quarter of the output's side)
//! against the frame it estimates, on lavapipe, for scenes with one light and one pass, several lights, color
//! passes, both transports, dense and adaptive. Not a timing test: what it asserts is the estimate's
//! deterministic part, the photon count, within a factor of 2 of the frame's, and that the time splits into its
//! parts. The time against the frame's wall time is printed (measured on the 2-core CI machine kind: ratios 0.7
//! to 1.5, probes 0.08 to 0.3 of a several-second frame), not asserted: on a shared machine it is noise's to
//! decide. A two-interface frame under a second is mostly fixed cost, which the small probes' noise hides: that
//! case is a level-6 frame (3-4 s).
//!
//! Mesa's shader cache is off in this binary, so that the first renderer compiles its pipelines as on a machine
//! that has never run this build: a CPU driver compiles a pipeline when it first runs it, inside a timed probe
//! unless the estimate's first probe runs them all (a first render's estimate once said 59 s for a 1 s frame). The
//! first case estimates such a cold renderer; the renderers after it share the device's pipelines
//! (`caustics::Pipelines`) and compile only the variants their scenes add.

mod common;
use caustics::settings::{Method, Metric, Quality, Settings, Transport};
use caustics::FrameDesc;

#[test]
fn estimates_are_within_a_factor_of_two_of_the_frame() {
    // Before the device exists (this binary's only test).
    std::env::set_var("MESA_SHADER_CACHE_DISABLE", "true");
    let (_gpu, device) = common::gpu();
    // (scene, transport, method, level, camera, whether a small frame compiles the pipelines first).
    let cases: [(&str, Transport, Method, u32, &str, bool); 7] = [
        // A renderer that has compiled nothing: the estimate's probes compile what the frame runs.
        ("bunny.toml", Transport::Exact, Method::Adaptive, 3, "main", false),
        ("sphere.toml", Transport::Exact, Method::Adaptive, 3, "main", true),
        // The default configuration on a CPU device: a frame of several seconds.
        ("sphere.toml", Transport::Exact, Method::Adaptive, 4, "main", true),
        ("sphere.toml", Transport::TwoInterface, Method::Dense, 6, "main", true),
        ("bunny.toml", Transport::Exact, Method::Adaptive, 3, "main", true),
        ("two_lights.toml", Transport::Exact, Method::Adaptive, 3, "top", true),
        ("gallery.gltf", Transport::Exact, Method::Adaptive, 2, "main", true),
    ];
    for (name, transport, method, level, camera, warm) in cases {
        let quality =
            Quality { transport, method, metric: Metric::FluxError, level: Some(level), ..Quality::default() };
        let mut r = common::renderer(&device, &common::scene(name), Settings { quality, ..Settings::default() });
        let cam = r.scene().camera(Some(camera)).unwrap().clone();
        let view = r.camera_view(&cam, 256, 192);
        let desc = FrameDesc::new(&view, None);
        // A small frame first compiles the pipelines, a cost paid once per renderer whatever is rendered (on a
        // slower machine of the CI kind it alone came to 17 s, four times a 4 s frame); the probes' own cost is
        // what the band below holds.
        if warm {
            let small = r.camera_view(&cam, 64, 48);
            r.render(&FrameDesc::new(&small, None)).expect("warm-up frame");
        }
        let e = r.estimate(&desc).expect("estimate");
        let f = r.render(&desc).expect("frame");
        let actual = f.report.frame_ms * 1e-3;
        let ratio = e.wall_seconds() / actual;
        eprintln!(
            "{name} {transport:?} {method:?} level {level}{}: estimated {:.2} s (light {:.2}, eye {:.2}, record {:.2}, \
             {:.0} photons; probes {:.2} s), took {actual:.2} s ({} photons): ratio {ratio:.2}",
            if warm { "" } else { ", compiled by the probes" },
            e.wall_seconds(),
            e.light_seconds,
            e.eye_seconds,
            e.record_seconds,
            e.photons,
            e.probe_seconds,
            f.report.photons()
        );
        // The photons a frame will have are the estimate's deterministic part: the probes count them at lower
        // levels and the estimate extrapolates to the frame's.
        let photons = e.photons / f.report.photons() as f64;
        eprintln!("{name}: photons estimated / rendered {photons:.2}");
        assert!(
            (0.5..=2.0).contains(&photons),
            "{name}: {:.0} photons estimated, {} rendered",
            e.photons,
            f.report.photons()
        );
        // The time splits into its parts.
        assert!(e.light_seconds > 0.0 && e.eye_seconds > 0.0 && e.record_seconds >= 0.0, "{e:?}");
        assert!((e.light_seconds + e.eye_seconds - e.seconds).abs() <= 1e-9 * e.seconds, "{e:?}");
    }
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}
