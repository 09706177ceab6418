//! How raykin talks on stderr: one line per message, `raykin: warning: ...`, without colour codes (logs and
//! CI files stay readable), and without third-party noise a newcomer's first run would otherwise start
//! with (Mesa's "XDG_RUNTIME_DIR is invalid" line).

use tracing::{Event, Level, Subscriber};
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields, format::Writer};
use tracing_subscriber::registry::LookupSpan;

/// Routes `tracing` events (the engine's warnings from inside the frame loop) to stderr in the same
/// one-line form as the CLI's own messages. `RUST_LOG` still selects what is shown (default: warnings).
pub fn init() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .with_ansi(false)
        .event_format(OneLine)
        .init();
}

struct OneLine;

impl<S, N> FormatEvent<S, N> for OneLine
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> std::fmt::Result {
        let level = match *event.metadata().level() {
            Level::ERROR => "error",
            Level::WARN => "warning",
            Level::INFO => "note",
            Level::DEBUG | Level::TRACE => "debug",
        };
        write!(writer, "raykin: {level}: ")?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

/// Gives the process a private runtime folder when `XDG_RUNTIME_DIR` is unset or unusable (containers, CI,
/// `sudo`): Mesa's Vulkan drivers probe for a Wayland display through it and print "XDG_RUNTIME_DIR is
/// invalid or not set" otherwise. Must run before any thread starts (it sets an environment variable).
#[cfg(unix)]
pub fn ensure_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let uid = current_uid();
    let usable = |dir: &std::path::Path| {
        dir.is_absolute()
            && std::fs::symlink_metadata(dir).is_ok_and(|m| {
                m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o777 == 0o700
            })
    };
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| usable(std::path::Path::new(&d))) {
        return;
    }
    let dir = std::env::temp_dir().join(format!("raykin-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    if usable(&dir) {
        // SAFETY: called first thing in `main`, before any other thread exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

#[cfg(not(unix))]
pub fn ensure_runtime_dir() {}

#[cfg(unix)]
fn current_uid() -> u32 {
    // SAFETY: getuid has no preconditions and cannot fail.
    unsafe { libc::getuid() }
}
