//! What the keys and the mouse do: moving, flying, the walk modes, τ, the budget, the
//! HUD, lines, boxes, the view from above, capturing the mouse, and quitting. Apart so
//! that the window's controls, listed at the top of the window's module, are read in
//! one place.

use winit::keyboard::KeyCode;
use winit::window::CursorGrabMode;

use super::{Change, WalkMode, WalkWindow};
use flaneur::walk::Move;

impl WalkWindow {
    pub(super) fn handle_keys(&mut self) {
        for (code, pressed) in std::mem::take(&mut self.events.keys) {
            let movement = match code {
                KeyCode::KeyW | KeyCode::ArrowUp => Some(Move::Forward),
                KeyCode::KeyS | KeyCode::ArrowDown => Some(Move::Back),
                KeyCode::KeyA | KeyCode::ArrowLeft => Some(Move::Left),
                KeyCode::KeyD | KeyCode::ArrowRight => Some(Move::Right),
                KeyCode::Space => Some(Move::Up),
                KeyCode::KeyC => Some(Move::Down),
                KeyCode::ShiftLeft | KeyCode::ShiftRight => Some(Move::Run),
                _ => None,
            };
            if let Some(m) = movement {
                self.steer.key(m, pressed);
                continue;
            }
            if !pressed {
                continue;
            }
            match code {
                KeyCode::KeyF => self.steer.fly = !self.steer.fly,
                KeyCode::KeyH => self.show_hud = !self.show_hud,
                KeyCode::KeyG => self.wireframe = !self.wireframe,
                KeyCode::KeyB => self.boxes = !self.boxes,
                KeyCode::KeyT => self.top_view = !self.top_view,
                KeyCode::Digit1 => self.change = Some(Change::Mode(WalkMode::Review)),
                KeyCode::Digit2 => self.change = Some(Change::Mode(WalkMode::Box)),
                KeyCode::Digit3 => self.change = Some(Change::Mode(WalkMode::Pvs)),
                KeyCode::Digit4 => self.change = Some(Change::Mode(WalkMode::Visual)),
                KeyCode::Digit5 => self.change = Some(Change::Mode(WalkMode::Vsc)),
                KeyCode::Digit6 => self.change = Some(Change::Mode(WalkMode::Pb)),
                KeyCode::Digit7 => self.change = Some(Change::Mode(WalkMode::Conv)),
                KeyCode::BracketLeft | KeyCode::BracketRight => {
                    let factor = if code == KeyCode::BracketLeft {
                        0.5
                    } else {
                        2.0
                    };
                    // The walk's selection starts afresh under the new τ, as it did
                    // when the window kept it, even where the clamp leaves τ as it was.
                    if let Some(tau) = self.lod_tau {
                        self.lod_tau = Some((tau * factor).clamp(1e-5, 0.5));
                        self.lod_restart = true;
                    }
                }
                KeyCode::Minus => self.change = Some(Change::Budget(0.5)),
                KeyCode::Equal => self.change = Some(Change::Budget(2.0)),
                KeyCode::Escape if self.captured => self.capture(false),
                KeyCode::Escape | KeyCode::KeyQ => self.quit = true,
                _ => {}
            }
        }
    }

    pub(super) fn capture(&mut self, on: bool) {
        let Some(w) = &self.events.window else { return };
        if on {
            let grabbed = w
                .set_cursor_grab(CursorGrabMode::Locked)
                .or_else(|_| w.set_cursor_grab(CursorGrabMode::Confined));
            if grabbed.is_err() {
                return;
            }
        } else {
            let _ = w.set_cursor_grab(CursorGrabMode::None);
        }
        w.set_cursor_visible(!on);
        self.captured = on;
    }
}
