//! Scripted input for `specula view --script FILE`: what a user would do, frame by frame,
//! fed to the same handlers as the window's events (headless tests, reproducible demos).
//! One action a line, `FRAME ACTION ARGS`, `#` starts a comment:
//!
//! ```text
//! 0  key w down        # hold a movement key (w a s d q e shift) ...
//! 20 key w up          # ... and let it go
//! 21 look 40 -10       # mouse motion in pixels with the look button held (orbit: drag)
//! 22 orbit             # toggle fly / orbit
//! 23 wheel 2           # wheel steps: orbit zoom, fly speed
//! 24 method glass refractor-map   # an object's method (`method * M` for the whole scene)
//! 25 knob cube_size=128
//! 26 pause             # pause / resume the glTF animations
//! 26 resize 320 200    # ask the window system for this inner size (the frame follows it)
//! 27 screenshot near   # DIR/near.png + .exr + .txt (the `specula render` camera arguments)
//! 30 quit
//! ```
//!
//! Frames advance by a fixed 1/30 s under a script, so a run is the same every time.

use std::path::Path;

use super::camera::Move;

#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    Key(Move, bool),
    Look(f32, f32),
    Orbit,
    Wheel(f32),
    /// An object's method (`None`: the whole scene's).
    Method(Option<String>, String),
    Knob(String),
    Pause,
    Resize(u32, u32),
    Screenshot(String),
    Quit,
}

/// The fixed time step of scripted frames.
pub const SCRIPT_DT: f32 = 1.0 / 30.0;

pub struct Script {
    /// (frame, action), in file order within a frame.
    steps: Vec<(u64, Action)>,
}

pub fn key_named(name: &str) -> Option<Move> {
    Some(match name.to_ascii_lowercase().as_str() {
        "w" => Move::Forward,
        "s" => Move::Back,
        "a" => Move::Left,
        "d" => Move::Right,
        "e" => Move::Up,
        "q" => Move::Down,
        "shift" => Move::Fast,
        _ => return None,
    })
}

impl Script {
    pub fn load(path: &Path) -> specula::Result<Script> {
        let text = std::fs::read_to_string(path).map_err(|e| specula::Error::io(path, e))?;
        Script::parse(&text).map_err(|(line, m)| specula::Error::invalid(format!("{} line {line}", path.display()), m))
    }

    /// The actions, or the first bad line's number and what is wrong with it.
    pub fn parse(text: &str) -> Result<Script, (usize, String)> {
        let mut steps = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let bad = |m: String| (i + 1, m);
            let words: Vec<&str> = line.split_whitespace().collect();
            let frame: u64 = words[0].parse().map_err(|_| bad(format!("'{}' is not a frame number", words[0])))?;
            let args = &words[1..];
            let num = |k: usize| -> Result<f32, (usize, String)> {
                let w = args.get(k).ok_or_else(|| bad(format!("'{}' needs {} number(s)", args[0], k)))?;
                w.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| bad(format!("'{w}' is not a finite number")))
            };
            let want = |n: usize| {
                if args.len() == n + 1 {
                    Ok(())
                } else {
                    Err(bad(format!("'{}' takes {n} argument(s), got {}", args[0], args.len() - 1)))
                }
            };
            let Some(&verb) = args.first() else { return Err(bad("a frame number without an action".into())) };
            let action = match verb {
                "key" => {
                    want(2)?;
                    let m = key_named(args[1]).ok_or_else(|| bad(format!("unknown key '{}' (w a s d q e shift)", args[1])))?;
                    let down = match args[2] {
                        "down" => true,
                        "up" => false,
                        other => return Err(bad(format!("'{other}' is not down or up"))),
                    };
                    Action::Key(m, down)
                }
                "look" => {
                    want(2)?;
                    Action::Look(num(1)?, num(2)?)
                }
                "orbit" => {
                    want(0)?;
                    Action::Orbit
                }
                "wheel" => {
                    want(1)?;
                    Action::Wheel(num(1)?)
                }
                "method" => {
                    want(2)?;
                    let object = (args[1] != "*").then(|| args[1].to_string());
                    Action::Method(object, args[2].to_string())
                }
                "knob" => {
                    want(1)?;
                    Action::Knob(args[1].to_string())
                }
                "pause" => {
                    want(0)?;
                    Action::Pause
                }
                "resize" => {
                    want(2)?;
                    let side = |k: usize| {
                        args[k]
                            .parse::<u32>()
                            .ok()
                            .filter(|v| (1..=16384).contains(v))
                            .ok_or_else(|| bad(format!("'{}' is not a size in 1..=16384", args[k])))
                    };
                    Action::Resize(side(1)?, side(2)?)
                }
                "screenshot" => {
                    want(1)?;
                    let name = args[1];
                    if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
                        return Err(bad(format!("screenshot name '{name}' may hold only letters, digits, - and _")));
                    }
                    Action::Screenshot(name.to_string())
                }
                "quit" => {
                    want(0)?;
                    Action::Quit
                }
                other => {
                    return Err(bad(format!(
                        "unknown action '{other}' (key, look, orbit, wheel, method, knob, pause, resize, screenshot, quit)"
                    )))
                }
            };
            steps.push((frame, action));
        }
        steps.sort_by_key(|(f, _)| *f);
        Ok(Script { steps })
    }

    /// The actions of frame `frame`.
    pub fn at(&self, frame: u64) -> impl Iterator<Item = &Action> {
        self.steps.iter().filter(move |(f, _)| *f == frame).map(|(_, a)| a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_action_in_frame_order() {
        let s =
            Script::parse("5 quit\n0 key w down # hold\n\n2 look 3 -4\n2 method glass bvh\n3 method * auto\n4 screenshot a_1\n").unwrap();
        assert_eq!(s.at(0).collect::<Vec<_>>(), [&Action::Key(Move::Forward, true)]);
        assert_eq!(s.at(2).collect::<Vec<_>>(), [&Action::Look(3.0, -4.0), &Action::Method(Some("glass".into()), "bvh".into())]);
        assert_eq!(s.at(3).collect::<Vec<_>>(), [&Action::Method(None, "auto".into())]);
        assert_eq!(s.at(5).collect::<Vec<_>>(), [&Action::Quit]);
    }

    #[test]
    fn bad_lines_name_the_line_and_the_word() {
        for (text, line, what) in [
            ("x quit", 1, "'x' is not a frame number"),
            ("0 key z down", 1, "unknown key 'z'"),
            ("0 quit\n1 look 1 nan", 2, "'nan' is not a finite number"),
            ("0 look 1", 1, "'look' takes 2 argument(s), got 1"),
            ("0 jump", 1, "unknown action 'jump'"),
            ("0 screenshot ../x", 1, "may hold only"),
            ("0 resize 0 10", 1, "'0' is not a size"),
        ] {
            let (l, m) = Script::parse(text).err().unwrap();
            assert_eq!(l, line, "{text}: {m}");
            assert!(m.contains(what), "{text}: {m}");
        }
    }
}
