//! Exports the editor runs in the background (the mesh, the picture) with the command
//! line's code, reporting a message when each ends.

use std::sync::mpsc::{Receiver, channel};

/// Exports running in the background.
#[derive(Default)]
pub struct Exports {
    /// The running export's message, when it ends.
    pub running: Option<Receiver<String>>,
}

impl Exports {
    /// The message of a finished export, if one finished.
    pub fn finished(&mut self) -> Option<String> {
        let msg = self.running.as_ref()?.try_recv().ok()?;
        self.running = None;
        Some(msg)
    }

    /// Runs `work` on a thread; its message is reported when it ends.
    pub fn start(&mut self, ctx: &egui::Context, work: impl FnOnce() -> String + Send + 'static) {
        let (tx, rx) = channel();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let _ = tx.send(work());
            ctx.request_repaint();
        });
        self.running = Some(rx);
    }
}
