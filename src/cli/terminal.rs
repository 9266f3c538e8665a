//! Text for the terminal: one safe line on stderr, clap's message as one line.

use std::io::Write as _;

/// Writes one line to stderr: `text`, with what came from files (a scene's name, a model's
/// file name, a line of a scene file) made safe for a terminal
/// ([`raylab_core::base::inputs::escape_control`]: control characters escaped, a line break
/// included, so the message stays one line). A stderr that cannot be written (`2> /dev/full`)
/// is no panic: the exit code still says what happened.
pub(super) fn print_error_line(text: &str) {
    let _ = writeln!(
        std::io::stderr(),
        "{}",
        raylab_core::base::inputs::escape_control(text)
    );
}

/// `text` of several lines made safe for a terminal line by line (see [`print_error_line`]).
pub(super) fn printable_lines(text: &str) -> String {
    text.lines()
        .map(|line| format!("{}\n", raylab_core::base::inputs::escape_control(line)))
        .collect()
}

/// clap's message as one line: its first, with what it lists after a colon ("the following
/// required arguments were not provided: --pixel <X,Y>").
pub(super) fn one_line(text: &str) -> String {
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("error: bad arguments");
    if !first.ends_with(':') {
        return first.to_owned();
    }
    let listed: Vec<&str> = lines
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .collect();
    format!("{first} {}", listed.join(", "))
}
