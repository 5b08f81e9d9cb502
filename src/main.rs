mod cli;

use clap::Parser;

/// The error and its causes on one line. Library errors already print their source in their own
/// message ("file: No such file or directory"), so a cause whose text the line already holds is not
/// repeated.
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// A command piped into `head` or `less` ends quietly when the reader closes the pipe, as Unix
/// tools do: Rust ignores SIGPIPE by default, which turns the next `println!` into a panic.
#[cfg(unix)]
fn end_quietly_on_closed_pipe() {
    // SAFETY: restoring a signal's default disposition at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn end_quietly_on_closed_pipe() {}

fn main() {
    let cli = cli::Cli::parse();
    // The editor keeps Rust's behaviour: a closed pipe on its log is an error it survives, not
    // the end of an artist's session.
    if !matches!(cli.command, None | Some(cli::Command::Edit(_))) {
        end_quietly_on_closed_pipe();
    }
    if let Err(e) = cli::run(cli) {
        eprintln!("error: {}", one_line(&e));
        std::process::exit(1);
    }
}
