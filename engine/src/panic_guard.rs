//! Runs code that must not take the process down, such as third-party decoders fed untrusted files: a panic
//! becomes an error carrying its message and location, and the default hook does not print it (the caller
//! reports it once, as an error naming the input).

use std::cell::{Cell, RefCell};
use std::panic::{AssertUnwindSafe, PanicHookInfo};

std::thread_local! {
    static GUARDED: Cell<bool> = const { Cell::new(false) };
    static CAUGHT: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Runs `f`; a panic inside it is returned as `Err(message at file:line)`.
pub fn catch<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static INSTALL: std::sync::Once = std::sync::Once::new();
    INSTALL.call_once(|| {
        // Panics outside a guarded call still reach the hook that was installed before.
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if GUARDED.get() {
                CAUGHT.set(Some(describe(info)));
            } else {
                previous(info);
            }
        }));
    });
    let outer = GUARDED.replace(true);
    let result = std::panic::catch_unwind(AssertUnwindSafe(f));
    GUARDED.set(outer);
    result.map_err(|_| {
        CAUGHT
            .take()
            .unwrap_or_else(|| "a panic without a message".into())
    })
}

fn describe(info: &PanicHookInfo) -> String {
    let payload = info.payload();
    let message = payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "(no message)".into());
    match info.location() {
        Some(at) => format!("{message} (at {}:{})", at.file(), at.line()),
        None => message,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_panic_becomes_an_error_with_its_location() {
        let err = super::catch(|| -> u32 { panic!("decoder bug") }).unwrap_err();
        assert!(
            err.starts_with("decoder bug (at ") && err.contains("panic_guard.rs"),
            "{err}"
        );
        assert_eq!(super::catch(|| 7).unwrap(), 7);
    }
}
