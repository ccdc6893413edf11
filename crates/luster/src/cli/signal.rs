//! The process's Ctrl-C / SIGTERM handler: removes the images being written
//! and exits with status 130, so an interrupted render leaves no temporaries.

/// Installs the handler. Failing to install it is not fatal.
pub fn remove_temporaries_on_signal() -> Result<(), String> {
    ctrlc::set_handler(|| {
        for t in luster_core::image::output::temporaries_in_progress() {
            let _ = std::fs::remove_file(t);
        }
        std::process::exit(130);
    })
    .map_err(|e| e.to_string())
}
