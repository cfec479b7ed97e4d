//! `--script FILE`: actions replayed at given frame numbers, so that a run is the same on
//! every machine however long its frames take. One action per line:
//!
//! ```text
//! # comment (also after an action)
//! FRAME ACTION ARGS...
//! ```
//!
//! The actions and their arguments are listed in `docs/demo.md` and the crate docs; a line
//! that does not parse is `FILE:LINE: problem`.

use std::path::{Path, PathBuf};

use crate::camera::Axis;
use crate::scene::{Backend, Method};
use tessera_core::catmull_clark::FirstSplit;

/// One thing the script does.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Turns the view about the up axis and up or down, degrees.
    Orbit { yaw: f32, pitch: f32 },
    /// Divides the distance to the target (above 1 moves closer).
    Zoom(f32),
    /// Moves the target across the view, in fractions of the view's height.
    Pan { right: f32, up: f32 },
    /// The default view of the model (the key `F`).
    Frame,
    /// The model's up axis (the view is framed again).
    Up(Axis),
    /// A parameter of the tessellation or of the drawing.
    Set(Setting),
    /// Animation of the control points on, off or toggled.
    Animate(Option<bool>),
    /// Control points back at rest, animation time zero.
    Reset,
    /// Opens another file (as if picked from the menu).
    Load(PathBuf),
    /// Saves this frame as a PNG.
    Screenshot(PathBuf),
}

/// A value the panel also sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    Method(Method),
    /// Bézier edge-test threshold, model units (as `tessera render --threshold`).
    Threshold(f32),
    /// Catmull-Clark tolerance, fraction of the control box's diagonal (`--tolerance-rel`):
    /// the tolerance is then no longer in pixels.
    ToleranceRel(f64),
    /// Catmull-Clark tolerance in pixels of the view drawn (`--tolerance-px`).
    TolerancePx(f64),
    /// Catmull-Clark in pixels: the patches facing away from the eye are culled too.
    CullBackfaces(bool),
    MaxDepth(u32),
    FirstSplit(FirstSplit),
    /// Uniform methods: segments per patch side.
    Segments(u32),
    Wireframe(bool),
    PatchTint(bool),
    Backend(Backend),
}

/// An action with the frame it runs at and the line it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub frame: u32,
    pub line: usize,
    pub action: Action,
}

/// A parsed script: its steps in frame order (lines of one frame in file order).
#[derive(Clone, Debug, Default)]
pub struct Script {
    pub path: PathBuf,
    pub steps: Vec<Step>,
}

impl Script {
    /// Reads and parses `path`; `frames` is the run's length (a step past it is an error).
    pub fn load(path: &Path, frames: u32) -> Result<Script, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse(path, &text, frames)
    }

    /// Parses `text` as the contents of `path`.
    pub fn parse(path: &Path, text: &str, frames: u32) -> Result<Script, String> {
        let mut steps = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let code = raw.split('#').next().unwrap_or("").trim();
            if code.is_empty() {
                continue;
            }
            let step = parse_line(code, frames)
                .map_err(|msg| format!("{}:{line}: {msg}", path.display()))?;
            steps.push(Step {
                frame: step.0,
                line,
                action: step.1,
            });
        }
        // Stable: the lines of one frame keep their order.
        steps.sort_by_key(|s| s.frame);
        Ok(Script {
            path: path.to_path_buf(),
            steps,
        })
    }

    /// The steps of `frame`, in order.
    pub fn at(&self, frame: u32) -> impl Iterator<Item = &Step> {
        self.steps.iter().filter(move |s| s.frame == frame)
    }

    /// `FILE:LINE: msg` for a step that could not be carried out.
    pub fn error_at(&self, step: &Step, msg: impl std::fmt::Display) -> String {
        format!("{}:{}: {msg}", self.path.display(), step.line)
    }
}

fn parse_line(code: &str, frames: u32) -> Result<(u32, Action), String> {
    let mut words = code.split_whitespace();
    let frame_word = words.next().unwrap_or("");
    let frame: u32 = frame_word
        .parse()
        .map_err(|_| format!("{frame_word:?} is not a frame number (FRAME ACTION ARGS...)"))?;
    if frame >= frames {
        return Err(format!(
            "frame {frame} is past the run's last frame ({})",
            frames.saturating_sub(1)
        ));
    }
    let Some(name) = words.next() else {
        return Err(format!("frame {frame}: an action is missing"));
    };
    let args: Vec<&str> = words.collect();
    let want = |n: usize, usage: &str| {
        if args.len() == n {
            Ok(())
        } else {
            Err(format!(
                "{name} takes {n} argument{} ({usage}), got {}",
                if n == 1 { "" } else { "s" },
                args.len()
            ))
        }
    };
    let action = match name {
        "orbit" => {
            want(2, "orbit YAW PITCH, degrees")?;
            Action::Orbit {
                yaw: number(args[0], "yaw")?,
                pitch: number(args[1], "pitch")?,
            }
        }
        "zoom" => {
            want(1, "zoom FACTOR, above 1 moves closer")?;
            let f: f32 = number(args[0], "zoom factor")?;
            if f <= 0.0 {
                return Err(format!("zoom factor {f} must be above 0"));
            }
            Action::Zoom(f)
        }
        "pan" => {
            want(2, "pan RIGHT UP, fractions of the view's height")?;
            Action::Pan {
                right: number(args[0], "pan right")?,
                up: number(args[1], "pan up")?,
            }
        }
        "frame" => {
            want(0, "frame")?;
            Action::Frame
        }
        "up" => {
            want(1, "up x|y|z")?;
            Action::Up(Axis::parse(args[0]).ok_or_else(|| {
                format!("up axis {:?} is not x, y or z", args[0])
            })?)
        }
        "set" => {
            want(2, "set KEY VALUE")?;
            Action::Set(setting(args[0], args[1])?)
        }
        "animate" => {
            want(1, "animate on|off|toggle")?;
            Action::Animate(match args[0] {
                "toggle" => None,
                v => Some(switch(v)?),
            })
        }
        "reset" => {
            want(0, "reset")?;
            Action::Reset
        }
        "load" => {
            want(1, "load FILE")?;
            Action::Load(PathBuf::from(args[0]))
        }
        "screenshot" => {
            want(1, "screenshot FILE.png")?;
            let path = PathBuf::from(args[0]);
            check_png(&path)?;
            Action::Screenshot(path)
        }
        other => {
            return Err(format!(
                "unknown action {other:?} (orbit, zoom, pan, frame, up, set, animate, reset, load, screenshot)"
            ))
        }
    };
    Ok((frame, action))
}

/// Fails unless `path` ends in `.png` (any case).
pub fn check_png(path: &Path) -> Result<(), String> {
    let png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        Ok(())
    } else {
        Err(format!(
            "{}: a screenshot must be a .png file",
            path.display()
        ))
    }
}

fn number<T: std::str::FromStr>(word: &str, what: &str) -> Result<T, String> {
    word.parse::<T>()
        .map_err(|_| format!("{what} {word:?} is not a number"))
}

fn finite(word: &str, what: &str) -> Result<f64, String> {
    let v: f64 = number(word, what)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} {word} must be a positive number"))
    }
}

fn switch(word: &str) -> Result<bool, String> {
    match word {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        _ => Err(format!("{word:?} is not on or off")),
    }
}

/// `set KEY VALUE`.
pub fn setting(key: &str, value: &str) -> Result<Setting, String> {
    Ok(match key {
        "method" => Setting::Method(Method::parse(value).ok_or_else(|| {
            format!(
                "method {value:?} is not one of map2p, map4p, map8p, flat, uniform (Bézier), adaptive, uniform (Catmull-Clark)"
            )
        })?),
        "threshold" => Setting::Threshold(finite(value, "threshold")? as f32),
        "tolerance-rel" => Setting::ToleranceRel(finite(value, "tolerance-rel")?),
        "tolerance-px" => Setting::TolerancePx(finite(value, "tolerance-px")?),
        "cull-backfaces" => Setting::CullBackfaces(switch(value)?),
        "max-depth" => Setting::MaxDepth(number(value, "max-depth")?),
        "first-split" => Setting::FirstSplit(match value {
            "search" => FirstSplit::Search,
            "midpoint" => FirstSplit::Midpoint,
            _ => return Err(format!("first-split {value:?} is not search or midpoint")),
        }),
        "segments" => {
            let n: u32 = number(value, "segments")?;
            if n == 0 {
                return Err("segments must be at least 1".into());
            }
            Setting::Segments(n)
        }
        "wireframe" => Setting::Wireframe(switch(value)?),
        "patch-tint" => Setting::PatchTint(switch(value)?),
        "backend" => Setting::Backend(match value {
            "gpu" => Backend::Gpu,
            "cpu" => Backend::Cpu,
            _ => return Err(format!("backend {value:?} is not gpu or cpu")),
        }),
        _ => {
            return Err(format!(
                "unknown setting {key:?} (method, threshold, tolerance-rel, tolerance-px, cull-backfaces, max-depth, first-split, segments, wireframe, patch-tint, backend)"
            ))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Script, String> {
        Script::parse(Path::new("s.txt"), text, 100)
    }

    #[test]
    fn every_action_parses_and_steps_sort_by_frame() {
        let s = parse(
            "# a comment\n\
             \n\
             9 orbit 30 -10   # trailing comment\n\
             2 zoom 1.5\n\
             2 pan 0.1 -0.2\n\
             3 frame\n\
             4 up y\n\
             5 set tolerance-rel 3e-4\n\
             5 set method map8p\n\
             6 animate toggle\n\
             6 animate on\n\
             7 reset\n\
             8 load assets/teaset/teacup\n\
             99 screenshot out.PNG\n",
        )
        .expect("parses");
        let frames: Vec<u32> = s.steps.iter().map(|s| s.frame).collect();
        assert_eq!(frames, [2, 2, 3, 4, 5, 5, 6, 6, 7, 8, 9, 99]);
        assert_eq!(s.steps[0].action, Action::Zoom(1.5));
        assert_eq!(s.steps[0].line, 4);
        assert_eq!(
            s.steps[1].action,
            Action::Pan {
                right: 0.1,
                up: -0.2
            }
        );
        assert_eq!(s.steps[4].action, Action::Set(Setting::ToleranceRel(3e-4)));
        assert_eq!(
            s.steps[5].action,
            Action::Set(Setting::Method(Method::Map8p))
        );
        assert_eq!(s.steps[6].action, Action::Animate(None));
        assert_eq!(s.steps[7].action, Action::Animate(Some(true)));
        assert_eq!(
            s.steps[10].action,
            Action::Orbit {
                yaw: 30.0,
                pitch: -10.0
            }
        );
        assert_eq!(s.at(6).count(), 2);
        let px = parse("3 set tolerance-px 0.5\n").expect("parses");
        assert_eq!(px.steps[0].action, Action::Set(Setting::TolerancePx(0.5)));
    }

    #[test]
    fn bad_lines_name_the_file_and_line() {
        for (text, want) in [
            ("x orbit 1 2", "s.txt:1: \"x\" is not a frame number"),
            ("\n\n3 spin 1", "s.txt:3: unknown action \"spin\""),
            ("1 orbit 1", "s.txt:1: orbit takes 2 arguments"),
            ("1 zoom -2", "s.txt:1: zoom factor -2 must be above 0"),
            ("1 zoom abc", "s.txt:1: zoom factor \"abc\" is not a number"),
            ("1 up w", "s.txt:1: up axis \"w\" is not x, y or z"),
            ("1 set colour red", "s.txt:1: unknown setting \"colour\""),
            (
                "1 set tolerance-rel 0",
                "s.txt:1: tolerance-rel 0 must be a positive number",
            ),
            (
                "1 set tolerance-px -1",
                "s.txt:1: tolerance-px -1 must be a positive number",
            ),
            (
                "1 set threshold nan",
                "s.txt:1: threshold nan must be a positive number",
            ),
            (
                "1 set method catmull",
                "s.txt:1: method \"catmull\" is not one of",
            ),
            (
                "1 set wireframe maybe",
                "s.txt:1: \"maybe\" is not on or off",
            ),
            (
                "1 screenshot a.jpg",
                "s.txt:1: a.jpg: a screenshot must be a .png file",
            ),
            (
                "100 frame",
                "s.txt:1: frame 100 is past the run's last frame (99)",
            ),
            ("7", "s.txt:1: frame 7: an action is missing"),
        ] {
            let e = parse(text).expect_err(text);
            assert!(e.starts_with(want), "{text:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn a_missing_file_is_one_line() {
        let e = Script::load(Path::new("/nonexistent/s.txt"), 5).expect_err("missing");
        assert!(e.starts_with("/nonexistent/s.txt: "), "{e}");
    }
}
