//! The shadow maps kept with a scene ([`ShadowCache`]): per light, the map the first
//! picture that needs it makes, shared by every later picture of the scene.
//!
//! The cache holds each map as `dyn Any` and hands it back as the type it is asked for,
//! so that the scene, which owns the cache, needs nothing of the renderer that makes and
//! reads the maps (`raster`).

use std::any::Any;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

/// A kept map, of whatever type the renderer made it; `None` when the light has nothing
/// to shadow.
type Kept = Option<Arc<dyn Any + Send + Sync>>;

/// The shadow maps of a scene's own lights, made on first use and kept with the scene:
/// they depend on the scene and the light, not on the camera, so every picture of one
/// revision shares them. A sun's kept map covers the whole scene; a point light's is a
/// cube around it.
///
/// Precondition: the scene does not change after its first shaded picture (a scene is
/// one revision of the world); a caller that edits a scene in place calls
/// [`ShadowCache::clear`]. A clone of a scene starts with no maps.
#[derive(Default)]
pub struct ShadowCache {
    /// Per light (index into [`Scene::lights`](super::Scene::lights)), its map once made.
    kept: Mutex<Vec<(usize, Arc<OnceLock<Kept>>)>>,
}

impl ShadowCache {
    /// The map of type `T` kept for light `light`, made by `make` if it is not there yet:
    /// `None` when `make` made none, or when the map kept for the light is not a `T`. Two
    /// pictures asking at once share one making.
    pub(in crate::render) fn get<T: Any + Send + Sync>(
        &self,
        light: usize,
        make: impl FnOnce() -> Option<T>,
    ) -> Option<Arc<T>> {
        let cell = {
            let mut kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
            match kept.iter().find(|(l, _)| *l == light) {
                Some((_, cell)) => Arc::clone(cell),
                None => {
                    let cell = Arc::new(OnceLock::new());
                    kept.push((light, Arc::clone(&cell)));
                    cell
                }
            }
        };
        let map = cell.get_or_init(|| make().map(|m| Arc::new(m) as Arc<dyn Any + Send + Sync>));
        Arc::clone(map.as_ref()?).downcast::<T>().ok()
    }

    /// The map of type `T` kept for light `light`, if one has been made.
    #[cfg(test)]
    pub(in crate::render) fn made<T: Any + Send + Sync>(&self, light: usize) -> Option<Arc<T>> {
        let kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
        let (_, cell) = kept.iter().find(|(l, _)| *l == light)?;
        Arc::clone(cell.get()?.as_ref()?).downcast::<T>().ok()
    }

    /// How many maps are kept.
    pub fn len(&self) -> usize {
        let kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
        kept.iter().filter(|(_, cell)| cell.get().is_some()).count()
    }

    /// Whether no map is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Forgets every kept map.
    pub fn clear(&mut self) {
        self.kept
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .clear();
    }
}

impl Clone for ShadowCache {
    /// An empty cache: maps are made again for the copy.
    fn clone(&self) -> ShadowCache {
        ShadowCache::default()
    }
}

impl std::fmt::Debug for ShadowCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowCache")
            .field("maps", &self.len())
            .finish()
    }
}
