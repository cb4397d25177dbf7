//! Progress bars on stderr for the long CPU jobs (bakes, reference renders).

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Mutex;

/// Run a bake with a progress bar on stderr: `bake` gets the library's progress callback.
pub fn with_progress_bar<T, E>(
    prefix: String,
    bake: impl FnOnce(lightlab_bake::Progress) -> Result<T, E>,
) -> Result<T>
where
    E: std::error::Error + Send + Sync + 'static,
{
    let bar = ProgressBar::new(1);
    bar.set_style(
        ProgressStyle::with_template("{prefix} {msg} [{bar:30}] {pos}/{len}, {elapsed}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(prefix);
    let last = Mutex::new(String::new());
    let out = bake(&|stage, done, total| {
        let mut l = last.lock().expect("progress lock");
        if *l != stage {
            *l = stage.to_string();
            bar.set_message(stage.to_string());
        }
        bar.set_length(total.max(done).max(1) as u64);
        bar.set_position(done as u64);
        true
    });
    bar.finish_and_clear();
    Ok(out?)
}
