//! Cameras and lights, by name: one [`Register`] for each kind, the same rules for both.

use crate::model::camera::{Camera, Light};

use super::*;

/// A thing the world keeps by name beside its bodies: a camera, a light.
pub trait Named: Clone {
    /// Checks the thing before it is stored: the copy to keep, or why it is refused.
    fn validated(&self) -> Result<Self, WorldError>;
    /// The refusal for a name under which nothing of this kind is kept.
    fn unknown(name: &str) -> WorldError;
}

impl Named for Camera {
    fn validated(&self) -> Result<Self, WorldError> {
        Ok(Camera::validated(self)?)
    }
    fn unknown(name: &str) -> WorldError {
        WorldError::UnknownCamera(name.to_owned())
    }
}

impl Named for Light {
    fn validated(&self) -> Result<Self, WorldError> {
        Ok(Light::validated(self)?)
    }
    fn unknown(name: &str) -> WorldError {
        WorldError::UnknownLight(name.to_owned())
    }
}

/// Things of one kind by name, in name order. Serialized as a map from name to thing.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(
    transparent,
    bound(serialize = "T: Serialize", deserialize = "T: Deserialize<'de>")
)]
pub struct Register<T>(BTreeMap<String, T>);

impl<T> Default for Register<T> {
    fn default() -> Self {
        Register(BTreeMap::new())
    }
}

impl<T: Named> Register<T> {
    /// The thing named `name`.
    pub fn get(&self, name: &str) -> Option<&T> {
        self.0.get(name)
    }

    /// Every thing, by name, in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &T)> + '_ {
        self.0.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// How many there are.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Stores (or replaces) `thing` under `name`. Refused, changing nothing, for a bad
    /// name or a thing that [`Named::validated`] refuses. Inverse: [`Register::remove`]
    /// (or storing the thing replaced).
    fn set(&mut self, name: &str, thing: &T) -> Result<(), WorldError> {
        valid_name(name)?;
        let thing = thing.validated()?;
        self.0.insert(name.to_owned(), thing);
        Ok(())
    }

    /// Removes the thing named `name` and returns it. Refused, changing nothing, if
    /// there is none.
    fn remove(&mut self, name: &str) -> Result<T, WorldError> {
        self.0.remove(name).ok_or_else(|| T::unknown(name))
    }
}

impl World {
    /// The cameras, by name.
    pub fn camera_register(&self) -> &Register<Camera> {
        &self.cameras
    }

    /// The lights, by name.
    pub fn light_register(&self) -> &Register<Light> {
        &self.lights
    }

    /// The camera with this name.
    pub fn camera(&self, name: &str) -> Option<&Camera> {
        self.cameras.get(name)
    }

    /// Every camera, by name.
    pub fn cameras(&self) -> impl Iterator<Item = (&str, &Camera)> + '_ {
        self.cameras.iter()
    }

    /// The light with this name.
    pub fn light(&self, name: &str) -> Option<&Light> {
        self.lights.get(name)
    }

    /// Every light, by name.
    pub fn lights(&self) -> impl Iterator<Item = (&str, &Light)> + '_ {
        self.lights.iter()
    }

    /// Stores (or replaces) the camera `name`. Refused for a bad name or camera.
    pub fn set_camera(&mut self, name: &str, camera: Camera) -> Result<(), WorldError> {
        self.cameras.set(name, &camera)?;
        self.written();
        Ok(())
    }

    /// Removes the camera `name` and returns it. Refused if there is none.
    pub fn remove_camera(&mut self, name: &str) -> Result<Camera, WorldError> {
        let c = self.cameras.remove(name)?;
        self.written();
        Ok(c)
    }

    /// Stores (or replaces) the light `name`. Refused for a bad name or light.
    pub fn set_light(&mut self, name: &str, light: Light) -> Result<(), WorldError> {
        self.lights.set(name, &light)?;
        self.written();
        Ok(())
    }

    /// Removes the light `name` and returns it. Refused if there is none.
    pub fn remove_light(&mut self, name: &str) -> Result<Light, WorldError> {
        let l = self.lights.remove(name)?;
        self.written();
        Ok(l)
    }
}
