//! The winit side of the window: the application handler that opens the window and
//! notes what its events asked for between two pumps. Apart because it only gathers;
//! what a key, a click or a resize does is decided where the walk's state is, when the
//! window is pumped for the next pose.

use std::sync::Arc;

use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The winit side: the window and what its events asked for since the last pump.
#[derive(Default)]
pub(super) struct Events {
    pub(super) window: Option<Arc<Window>>,
    pub(super) error: Option<String>,
    pub(super) size: (u32, u32),
    pub(super) title: String,
    /// Whether the window opens fitted to the screen (`ViewOptions::fit_screen`).
    pub(super) fit_screen: bool,
    pub(super) closed: bool,
    pub(super) resized: bool,
    pub(super) focus_lost: bool,
    pub(super) keys: Vec<(KeyCode, bool)>,
    pub(super) mouse: (f64, f64),
    pub(super) clicked: bool,
}

impl ApplicationHandler for Events {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        if self.fit_screen {
            // The window is not there yet to say which screen it is on: the primary
            // one, or the first the system lists (Wayland names no primary).
            let screen = event_loop
                .primary_monitor()
                .or_else(|| event_loop.available_monitors().next())
                .map(|m| m.size());
            if let Some(s) = screen {
                self.size = super::options::fit_to_screen(self.size, (s.width, s.height));
            }
        }
        let attributes = Window::default_attributes()
            .with_title(self.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(self.size.0, self.size.1));
        match event_loop.create_window(attributes) {
            Ok(w) => self.window = Some(Arc::new(w)),
            Err(e) => self.error = Some(format!("opening a window: {e}")),
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.closed = true,
            WindowEvent::Resized(size) => {
                self.size = (size.width, size.height);
                self.resized = true;
            }
            WindowEvent::Focused(false) => self.focus_lost = true,
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if !event.repeat {
                        self.keys.push((code, event.state == ElementState::Pressed));
                    }
                }
            }
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                button: MouseButton::Left,
                ..
            } => self.clicked = true,
            _ => {}
        }
    }

    fn device_event(&mut self, _: &ActiveEventLoop, _: winit::event::DeviceId, e: DeviceEvent) {
        if let DeviceEvent::MouseMotion { delta } = e {
            self.mouse.0 += delta.0;
            self.mouse.1 += delta.1;
        }
    }
}
