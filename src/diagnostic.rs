//! Diagnostics: the one error type every stage returns, rendered through
//! codespan-reporting the way rustc renders its errors.
//!
//! naga's own `diagnostic()` builders are crate-private, so this module builds
//! our [`Diagnostic`] from the public pieces naga exposes (`labels()` and
//! `message()` on parse errors, `spans()` on validation errors,
//! [`naga::Span::to_range`]). Every stage of the pipeline reports through
//! [`Error`], so a user sees the same shape of message whatever went wrong.

#![warn(missing_docs)]

use std::fmt;
use std::io::{IsTerminal, Write};
use std::ops::Range;
use std::sync::Arc;

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term;
use codespan_reporting::term::termcolor::{ColorChoice, StandardStream};

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// Something failed.
    Error,
    /// Something worked, with a caveat.
    Warning,
    /// Information.
    Note,
}

/// A span of the source with a message attached.
#[derive(Clone, Debug)]
pub struct Label {
    /// Byte range into the source text.
    pub range: Range<usize>,
    /// What the label says of its span.
    pub message: String,
    /// The primary label is the one the location (`path:line:col`) names.
    pub primary: bool,
}

/// A message about a shader, with labelled spans and trailing notes.
#[derive(Clone, Debug)]
pub struct Diagnostic {
    /// How serious it is.
    pub severity: Severity,
    /// The one-line message.
    pub message: String,
    /// The places in the file it points at.
    pub labels: Vec<Label>,
    /// Lines said after the source excerpt.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// A diagnostic of `severity` saying `message`, with no labels yet.
    pub fn new(severity: Severity, message: impl Into<String>) -> Self {
        Diagnostic {
            severity,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// An error saying `message`.
    pub fn error(message: impl Into<String>) -> Self {
        Self::new(Severity::Error, message)
    }

    /// Adds a label. The first label added is the primary one.
    pub fn with_label(mut self, range: Range<usize>, message: impl Into<String>) -> Self {
        let primary = self.labels.is_empty();
        self.labels.push(Label {
            range,
            message: message.into(),
            primary,
        });
        self
    }

    /// The diagnostic with one more note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// Converts a naga WGSL parse error, keeping all of its labels and notes.
    pub fn from_parse_error(error: &naga::front::wgsl::ParseError) -> Self {
        let mut diagnostic = Diagnostic::error(error.message());
        for (span, message) in error.labels() {
            if let Some(range) = span.to_range() {
                diagnostic = diagnostic.with_label(range, message);
            }
        }
        for note in error.notes() {
            diagnostic = diagnostic.with_note(note);
        }
        diagnostic
    }

    /// Converts a naga error that carries spans (validation errors), with the
    /// chain of `source()` causes as notes, as naga's own renderer does.
    pub fn from_spanned_error<E>(error: &naga::WithSpan<E>) -> Self
    where
        E: std::error::Error,
    {
        let mut diagnostic = Diagnostic::error(error.as_inner().to_string());
        for (span, message) in error.spans() {
            if let Some(range) = span.to_range() {
                diagnostic = diagnostic.with_label(range, message.clone());
            }
        }
        let mut cause = std::error::Error::source(error.as_inner());
        while let Some(source) = cause {
            diagnostic = diagnostic.with_note(source.to_string());
            cause = source.source();
        }
        diagnostic
    }

    fn to_codespan(&self) -> cs::Diagnostic<()> {
        let severity = match self.severity {
            Severity::Error => cs::Severity::Error,
            Severity::Warning => cs::Severity::Warning,
            Severity::Note => cs::Severity::Note,
        };
        let labels = self
            .labels
            .iter()
            .map(|label| {
                let style = if label.primary {
                    cs::LabelStyle::Primary
                } else {
                    cs::LabelStyle::Secondary
                };
                cs::Label::new(style, (), label.range.clone()).with_message(&label.message)
            })
            .collect();
        cs::Diagnostic::new(severity)
            .with_message(&self.message)
            .with_labels(labels)
            .with_notes(self.notes.clone())
    }
}

/// A source file as diagnostics see it: a display path and its text.
#[derive(Clone, Debug)]
pub struct SourceFile {
    /// The path as the user gave it (shown in diagnostics).
    pub path: String,
    /// The whole text.
    pub text: String,
}

impl SourceFile {
    /// A file named `path` holding `text`.
    pub fn new(path: impl Into<String>, text: impl Into<String>) -> Self {
        SourceFile {
            path: path.into(),
            text: text.into(),
        }
    }

    /// 1-based line and column (in characters) of a byte offset, as the
    /// rendered diagnostics print them.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = floor_char_boundary(&self.text, offset.min(self.text.len()));
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = self.text[line_start..offset].chars().count() + 1;
        (line, col)
    }
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// Replaces control characters (other than whitespace) by `?` of the same
/// byte length, so that a terminal is not driven by them and the byte ranges
/// of the labels still point at the same text.
fn sanitize(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() && !c.is_whitespace() {
                "?".repeat(c.len_utf8())
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Whether to colour rendered diagnostics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Color {
    /// Colour only when stderr is a terminal and `NO_COLOR` is not set.
    Auto,
    /// Always colour.
    Always,
    /// Never colour.
    Never,
}

impl Color {
    fn choice(self, is_terminal: bool) -> ColorChoice {
        match self {
            Color::Always => ColorChoice::Always,
            Color::Never => ColorChoice::Never,
            Color::Auto => {
                let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
                if !no_color && is_terminal {
                    ColorChoice::Auto
                } else {
                    ColorChoice::Never
                }
            }
        }
    }
}

/// The error every stage returns: a diagnostic, and the file it is about when
/// there is one (a missing file has none to show).
#[derive(Clone, Debug)]
pub struct Error {
    /// The file the diagnostic points into; `None` for one about no file.
    pub file: Option<Arc<SourceFile>>,
    /// What went wrong, and where.
    pub diagnostic: Diagnostic,
    /// A bug in shadecache rather than a fault of the input (the CLI exits
    /// 2 for it, 1 otherwise).
    pub internal: bool,
}

impl Error {
    /// An error about a file as a whole (cannot be read, is not a shader...).
    pub fn plain(diagnostic: Diagnostic) -> Self {
        Error {
            file: None,
            diagnostic,
            internal: false,
        }
    }

    /// A bug in shadecache: what went wrong, to report with the input.
    pub fn internal(diagnostic: Diagnostic) -> Self {
        Error {
            file: None,
            diagnostic,
            internal: true,
        }
    }

    /// An error whose labels point into `file`.
    pub fn in_file(file: Arc<SourceFile>, diagnostic: Diagnostic) -> Self {
        Error {
            file: Some(file),
            diagnostic,
            internal: false,
        }
    }

    /// Renders without colour, as it would appear in a log.
    pub fn render(&self) -> String {
        render_to_string(self.file.as_deref(), &self.diagnostic)
    }

    /// Writes the rendered diagnostic to stderr.
    pub fn emit_to_stderr(&self, color: Color) {
        emit_to_stderr(self.file.as_deref(), &self.diagnostic, color);
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render())
    }
}

impl std::error::Error for Error {}

fn simple_file(file: Option<&SourceFile>) -> SimpleFile<String, String> {
    match file {
        Some(file) => SimpleFile::new(file.path.clone(), sanitize(&file.text)),
        None => SimpleFile::new(String::new(), String::new()),
    }
}

fn codespan_of(file: Option<&SourceFile>, diagnostic: &Diagnostic) -> cs::Diagnostic<()> {
    let mut rendered = diagnostic.to_codespan();
    if file.is_none() {
        // Without a file there is nothing for labels to point into.
        rendered.labels.clear();
    }
    rendered
}

/// Renders a diagnostic without colour.
pub fn render_to_string(file: Option<&SourceFile>, diagnostic: &Diagnostic) -> String {
    let files = simple_file(file);
    let config = term::Config::default();
    // Rendering into a String only fails when a label points outside the
    // file, which the builders above never produce; fall back to the bare
    // message rather than lose the diagnostic.
    term::emit_into_string(&config, &files, &codespan_of(file, diagnostic))
        .unwrap_or_else(|_| format!("error: {}\n", diagnostic.message))
}

/// Writes a diagnostic to stderr, coloured according to `color`.
pub fn emit_to_stderr(file: Option<&SourceFile>, diagnostic: &Diagnostic, color: Color) {
    let stream = StandardStream::stderr(color.choice(std::io::stderr().is_terminal()));
    emit_to_stream(stream, file, diagnostic);
}

/// Writes a diagnostic to stdout (reports shown as compiler notes).
pub fn emit_to_stdout(file: Option<&SourceFile>, diagnostic: &Diagnostic, color: Color) {
    let stream = StandardStream::stdout(color.choice(std::io::stdout().is_terminal()));
    emit_to_stream(stream, file, diagnostic);
}

fn emit_to_stream(stream: StandardStream, file: Option<&SourceFile>, diagnostic: &Diagnostic) {
    let files = simple_file(file);
    let config = term::Config::default();
    let mut lock = stream.lock();
    if term::emit_to_write_style(&mut lock, &config, &files, &codespan_of(file, diagnostic))
        .is_err()
    {
        // A closed pipe or a label outside the file: keep the message at least.
        let _ = writeln!(lock, "{}", diagnostic.message);
    }
}
