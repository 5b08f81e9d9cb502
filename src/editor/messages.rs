//! What the editor tells the user: messages with a level, the last shown in the status bar, errors
//! kept on screen until dismissed. Errors and warnings go to stderr too (a headless run reads them
//! there).

use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Warning,
    Error,
}

#[derive(Clone, Debug)]
pub struct Message {
    pub level: Level,
    pub text: String,
    pub at: Instant,
}

/// The newest messages (at most [`MESSAGES_KEPT`]).
#[derive(Default)]
pub struct Messages {
    list: Vec<Message>,
}

/// Messages kept: enough for the errors window, bounded however long the editor runs.
const MESSAGES_KEPT: usize = 50;

impl Messages {
    pub fn push(&mut self, level: Level, text: impl Into<String>) {
        let text = text.into();
        match level {
            Level::Error => eprintln!("error: {text}"),
            Level::Warning => eprintln!("warning: {text}"),
            Level::Info => {}
        }
        self.list.push(Message {
            level,
            text,
            at: Instant::now(),
        });
        if self.list.len() > MESSAGES_KEPT {
            self.list.remove(0);
        }
    }

    pub fn last(&self) -> Option<&Message> {
        self.list.last()
    }

    pub fn iter(&self) -> impl Iterator<Item = &Message> {
        self.list.iter()
    }

    /// The errors not dismissed yet.
    pub fn errors(&self) -> impl Iterator<Item = &Message> {
        self.list.iter().filter(|m| m.level == Level::Error)
    }

    /// The errors window was dismissed: its errors stay in the list as warnings.
    pub fn dismiss_errors(&mut self) {
        for m in &mut self.list {
            if m.level == Level::Error {
                m.level = Level::Warning;
            }
        }
    }
}
