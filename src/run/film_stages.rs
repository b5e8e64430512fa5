//! The film's progress as two stages of a run: the tiles of base samples, then the adaptive samples
//! (bars on a terminal, log lines about every ten seconds otherwise), so that neither pass is silent.

use std::sync::Mutex;

use crate::film::{FilmProgress, TILE_SIZE_PX};
use crate::progress::{Progress, Stage};
use crate::scene::ImageSettings;

/// The tile stage until the adaptive pass starts, then the adaptive stage.
pub struct FilmStages<'a> {
    progress: &'a Progress,
    name: &'a str,
    tiles: Mutex<Option<Stage>>,
    adaptive: Mutex<Option<Stage>>,
}

impl<'a> FilmStages<'a> {
    /// Starts the tile stage `name` for `image`'s tiles.
    pub fn start(progress: &'a Progress, name: &'a str, image: &ImageSettings) -> Self {
        let tiles = image.width_px.div_ceil(TILE_SIZE_PX) * image.height_px.div_ceil(TILE_SIZE_PX);
        FilmStages {
            progress,
            name,
            tiles: Mutex::new(Some(progress.stage(name, tiles as u64, "tiles"))),
            adaptive: Mutex::new(None),
        }
    }

    /// Ends the stage still running with `summary` (with `-v`, printed with its time) and returns the
    /// adaptive pass's seconds (0 without one).
    pub fn finish(self, summary: &str) -> f64 {
        if let Some(stage) = self.tiles.into_inner().ok().flatten() {
            stage.finish(summary);
        }
        self.adaptive.into_inner().ok().flatten().map_or(0.0, |stage| stage.finish(summary).as_secs_f64())
    }
}

impl FilmProgress for FilmStages<'_> {
    fn tile_done(&self) {
        if let Ok(tiles) = self.tiles.lock() {
            if let Some(stage) = tiles.as_ref() {
                stage.inc(1);
            }
        }
    }

    fn adaptive_start(&self, pixels: u64, extra_samples: u64) {
        if let Some(stage) = self.tiles.lock().ok().and_then(|mut t| t.take()) {
            stage.finish("base samples");
        }
        let stage = self.progress.stage(&format!("{} adaptive", self.name), extra_samples, "samples");
        stage.set_message(format!("in {pixels} pixels"));
        if let Ok(mut adaptive) = self.adaptive.lock() {
            *adaptive = Some(stage);
        }
    }

    fn adaptive_done(&self, extra_samples: u64) {
        if let Ok(adaptive) = self.adaptive.lock() {
            if let Some(stage) = adaptive.as_ref() {
                stage.inc(extra_samples);
            }
        }
    }
}
