//! Cameras and lights, by name.

use crate::model::camera::{Camera, Light};

use super::*;

impl World {
    /// The camera with this name.
    pub fn camera(&self, name: &str) -> Option<&Camera> {
        self.cameras.get(name)
    }

    /// Every camera, by name.
    pub fn cameras(&self) -> impl Iterator<Item = (&str, &Camera)> + '_ {
        self.cameras.iter().map(|(k, c)| (k.as_str(), c))
    }

    /// The light with this name.
    pub fn light(&self, name: &str) -> Option<&Light> {
        self.lights.get(name)
    }

    /// Every light, by name.
    pub fn lights(&self) -> impl Iterator<Item = (&str, &Light)> + '_ {
        self.lights.iter().map(|(k, l)| (k.as_str(), l))
    }

    /// Stores (or replaces) the camera `name`. Refused for a bad name or camera.
    pub fn set_camera(&mut self, name: &str, camera: Camera) -> Result<(), WorldError> {
        valid_name(name)?;
        let camera = camera.validated()?;
        self.cameras.insert(name.to_owned(), camera);
        self.written();
        Ok(())
    }

    /// Removes the camera `name` and returns it. Refused if there is none.
    pub fn remove_camera(&mut self, name: &str) -> Result<Camera, WorldError> {
        let c = self
            .cameras
            .remove(name)
            .ok_or_else(|| WorldError::UnknownCamera(name.to_owned()))?;
        self.written();
        Ok(c)
    }

    /// Stores (or replaces) the light `name`. Refused for a bad name or light.
    pub fn set_light(&mut self, name: &str, light: Light) -> Result<(), WorldError> {
        valid_name(name)?;
        let light = light.validated()?;
        self.lights.insert(name.to_owned(), light);
        self.written();
        Ok(())
    }

    /// Removes the light `name` and returns it. Refused if there is none.
    pub fn remove_light(&mut self, name: &str) -> Result<Light, WorldError> {
        let l = self
            .lights
            .remove(name)
            .ok_or_else(|| WorldError::UnknownLight(name.to_owned()))?;
        self.written();
        Ok(l)
    }
}
