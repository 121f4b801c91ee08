//! `caustics view --script FILE`: scripted input, so that interactive frame rates can be measured again and again.
//! One step per line, `FRAMES VERB [ARGS]`, run one after another, one frame at a time; `#` starts a comment.
//!
//! | step | what each of its frames does |
//! |---|---|
//! | `N orbit DEG` | orbits the camera by DEG degrees (as a left-button drag) |
//! | `N drag DX DY` | drags the light by DX, DY pixels (as a right-button drag: x right, y down) |
//! | `N click FX FY` | clicks at FX, FY (fractions of the window's width and height from its top left): a drop into the water there |
//! | `N key NAME` | presses the key NAME of the controls table (`]`, `ArrowLeft`, `Space`, ...) on its first frame |
//! | `N drop FILE` | drops the scene FILE (relative to the script's folder) on the window on its first frame: it opens |
//! | `N still` | nothing: the viewer refines what the last change left |
//!
//! The viewer quits after the last step. Its stats gain a `script` list with, for each step: the frames presented,
//! their rate, the levels rendered and, once the step's changes stop, how long until the first frame at the chosen
//! level and full quality completed (`converged_ms`).

use super::controls::{Action, CONTROLS};
use caustics::error::{Error, Result};
use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verb {
    Orbit(f32),
    Drag(f32, f32),
    Key(Action),
    Click(f32, f32),
    /// A file dropped on the window: the script's `files[i]`.
    Drop(usize),
    Still,
}

#[derive(Clone, Debug)]
pub struct ScriptStep {
    /// The line of the script file (1-based).
    pub line: usize,
    pub frames: u32,
    pub verb: Verb,
    pub text: String,
}

/// What one step measured.
#[derive(Clone, Debug, Default)]
struct StepLog {
    started: Option<Instant>,
    last_present: Option<Instant>,
    presented: u32,
    completed: u32,
    levels: Option<(u32, u32)>,
    /// Milliseconds from the step's start to the first frame that completed at the chosen level, at full quality.
    converged_ms: Option<f64>,
}

pub struct Script {
    pub steps: Vec<ScriptStep>,
    /// The files its `drop` steps name, relative to the script's folder resolved.
    pub files: Vec<std::path::PathBuf>,
    current: usize,
    frame_in_step: u32,
    logs: Vec<StepLog>,
}

fn bad(path: &Path, line: usize, msg: &str) -> Error {
    Error::BadInput(format!("{}:{line}: {msg}", path.display()))
}

fn number(path: &Path, line: usize, what: &str, s: Option<&str>) -> Result<f32> {
    let s = s.ok_or_else(|| bad(path, line, &format!("missing {what}")))?;
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(bad(path, line, &format!("{what} `{s}` is not a finite number"))),
    }
}

impl Script {
    pub fn load(path: &Path) -> Result<Script> {
        let text =
            std::fs::read_to_string(path).map_err(|e| Error::BadInput(format!("--script {}: {e}", path.display())))?;
        Script::parse(path, &text)
    }

    pub fn parse(path: &Path, text: &str) -> Result<Script> {
        let mut steps = Vec::new();
        let mut files = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let body = raw.split('#').next().unwrap_or("").trim();
            if body.is_empty() {
                continue;
            }
            let mut words = body.split_whitespace();
            let count = words.next().unwrap_or("");
            let frames: u32 = count.parse().ok().filter(|&n| (1..=1_000_000).contains(&n)).ok_or_else(|| {
                bad(path, line, &format!("`{count}`: a step starts with its frame count (1 to 1000000)"))
            })?;
            let verb_word = words
                .next()
                .ok_or_else(|| bad(path, line, "missing the verb (orbit, drag, click, key, drop, still)"))?;
            let verb = match verb_word {
                "orbit" => Verb::Orbit(number(path, line, "the orbit angle (degrees per frame)", words.next())?),
                "drag" => {
                    let dx = number(path, line, "the drag's x (pixels per frame)", words.next())?;
                    let dy = number(path, line, "the drag's y (pixels per frame)", words.next())?;
                    Verb::Drag(dx, dy)
                }
                "key" => {
                    let name = words.next().ok_or_else(|| bad(path, line, "missing the key name"))?;
                    let action = CONTROLS
                        .iter()
                        .flat_map(|c| c.keys.iter())
                        .find(|(k, _)| k.eq_ignore_ascii_case(name))
                        .map(|(_, a)| *a)
                        .ok_or_else(|| {
                            bad(path, line, &format!("unknown key `{name}` (see `caustics view --print-controls`)"))
                        })?;
                    if matches!(action, Action::Quit | Action::Help | Action::Profile | Action::Trace) {
                        return Err(bad(path, line, &format!("key `{name}` is not scriptable")));
                    }
                    Verb::Key(action)
                }
                "click" => {
                    let fx = number(path, line, "the click's x (a fraction of the width)", words.next())?;
                    let fy = number(path, line, "the click's y (a fraction of the height)", words.next())?;
                    if !((0.0..=1.0).contains(&fx) && (0.0..=1.0).contains(&fy)) {
                        return Err(bad(path, line, &format!("click {fx} {fy}: both must lie in 0..=1")));
                    }
                    Verb::Click(fx, fy)
                }
                "drop" => {
                    let name = words.next().ok_or_else(|| bad(path, line, "missing the dropped file"))?;
                    let file = path.parent().unwrap_or(Path::new(".")).join(name);
                    if !file.is_file() {
                        return Err(bad(path, line, &format!("drop {name}: no such file ({})", file.display())));
                    }
                    files.push(file);
                    Verb::Drop(files.len() - 1)
                }
                "still" => Verb::Still,
                other => {
                    return Err(bad(
                        path,
                        line,
                        &format!("unknown verb `{other}` (expected orbit, drag, click, key, drop or still)"),
                    ))
                }
            };
            if let Some(extra) = words.next() {
                return Err(bad(path, line, &format!("unexpected `{extra}` after the step")));
            }
            steps.push(ScriptStep { line, frames, verb, text: body.to_string() });
        }
        if steps.is_empty() {
            return Err(Error::BadInput(format!("--script {}: no steps", path.display())));
        }
        let logs = vec![StepLog::default(); steps.len()];
        Ok(Script { steps, files, current: 0, frame_in_step: 0, logs })
    }

    /// Every frame the script still has to present.
    pub fn frames_left(&self) -> u64 {
        let rest: u64 = self.steps.iter().skip(self.current).map(|s| s.frames as u64).sum();
        rest - self.frame_in_step as u64
    }

    pub fn finished(&self) -> bool {
        self.current >= self.steps.len()
    }

    /// The input of the frame about to be drawn, and whether it is its step's first frame.
    pub fn begin_frame(&mut self) -> Option<(Verb, bool)> {
        let step = self.steps.get(self.current)?;
        let first = self.frame_in_step == 0;
        if first {
            self.logs[self.current].started = Some(Instant::now());
        }
        Some((step.verb, first))
    }

    /// The step whose frame is being drawn (the viewer keeps it with the frame until its report arrives).
    pub fn current_step(&self) -> usize {
        self.current
    }

    /// The frame was presented: count it, and move on to the next step after the step's last frame.
    pub fn presented(&mut self) {
        let Some(log) = self.logs.get_mut(self.current) else { return };
        log.presented += 1;
        log.last_present = Some(Instant::now());
        self.frame_in_step += 1;
        if self.frame_in_step >= self.steps[self.current].frames {
            self.current += 1;
            self.frame_in_step = 0;
        }
    }

    /// A frame of `step` completed, at `level` (`chosen` is the level it refines to), full quality unless
    /// `preview`.
    pub fn completed(&mut self, step: usize, level: u32, chosen: u32, preview: bool) {
        let Some(log) = self.logs.get_mut(step) else { return };
        log.completed += 1;
        log.levels = Some(log.levels.map_or((level, level), |(lo, hi)| (lo.min(level), hi.max(level))));
        if log.converged_ms.is_none() && level >= chosen && !preview {
            if let Some(t) = log.started {
                log.converged_ms = Some(t.elapsed().as_secs_f64() * 1e3);
            }
        }
    }

    pub fn stats(&self) -> Value {
        let rows: Vec<Value> = self
            .steps
            .iter()
            .zip(&self.logs)
            .map(|(s, l)| {
                let wall = match (l.started, l.last_present) {
                    (Some(a), Some(b)) => (b - a).as_secs_f64() * 1e3,
                    _ => 0.0,
                };
                json!({
                    "line": s.line,
                    "step": s.text,
                    "frames_presented": l.presented,
                    "frames_completed": l.completed,
                    "wall_ms": wall,
                    "fps": if wall > 0.0 { l.presented as f64 / (wall * 1e-3) } else { 0.0 },
                    "levels": l.levels.map(|(a, b)| [a, b]),
                    "converged_ms": l.converged_ms,
                })
            })
            .collect();
        Value::Array(rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_steps_and_names_the_bad_line() {
        let p = Path::new("moves.txt");
        let s = Script::parse(p, "# orbit then drag\n30 orbit 2\n\n10 drag 8 -2 # right\n1 key ]\n5 still\n").unwrap();
        assert_eq!(s.steps.len(), 4);
        assert_eq!(s.steps[0].verb, Verb::Orbit(2.0));
        assert_eq!(s.steps[1].verb, Verb::Drag(8.0, -2.0));
        assert_eq!(s.steps[1].line, 4);
        assert_eq!(s.steps[2].verb, Verb::Key(Action::IorUp));
        assert_eq!(s.frames_left(), 46);
        for (text, needle) in [
            ("10 fly 2", "moves.txt:1: unknown verb `fly`"),
            ("\n0 still", "moves.txt:2: `0`"),
            ("3 drag 1", "moves.txt:1: missing the drag's y"),
            ("3 orbit nan", "moves.txt:1: the orbit angle (degrees per frame) `nan`"),
            ("3 key F13", "moves.txt:1: unknown key `F13`"),
            ("3 key q", "moves.txt:1: key `q` is not scriptable"),
            ("3 still now", "moves.txt:1: unexpected `now`"),
            ("1 drop no-such-scene.toml", "moves.txt:1: drop no-such-scene.toml: no such file"),
            ("1 drop", "moves.txt:1: missing the dropped file"),
            ("# nothing", "no steps"),
        ] {
            let e = Script::parse(p, text).err().expect(text).to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn counts_frames_and_convergence_per_step() {
        let mut s = Script::parse(Path::new("m"), "2 drag 1 0\n3 still\n").unwrap();
        let mut verbs = Vec::new();
        let mut steps = Vec::new();
        while let Some((v, first)) = s.begin_frame() {
            verbs.push((v, first));
            steps.push(s.current_step());
            s.presented();
        }
        assert_eq!(verbs.len(), 5);
        assert!(verbs[0].1 && !verbs[1].1 && verbs[2].1);
        // Frames complete in order: two previews while dragging, then levels 2, 3 and 4 (chosen 4).
        for (step, (level, preview)) in
            steps.into_iter().zip([(2, true), (2, true), (2, false), (3, false), (4, false)])
        {
            s.completed(step, level, 4, preview);
        }
        let st = s.stats();
        assert_eq!(st[0]["levels"], json!([2, 2]));
        assert!(st[0]["converged_ms"].is_null());
        assert_eq!(st[1]["levels"], json!([2, 4]));
        assert!(st[1]["converged_ms"].as_f64().is_some());
        assert!(s.finished());
    }
}
