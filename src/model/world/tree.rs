//! The parts tree: attaching, detaching, naming, posing, colouring and killing bodies.

use crate::model::parts::{BodyId, Color};
use crate::model::pose::Pose;

use super::*;

impl World {
    /// ATTACH(b, supart): DETs `b` (with all its parts) from its supart and ATTs it to
    /// `supart`, at the end of its parts list. The body does not move: its pose is
    /// recomputed so that its world pose is unchanged. Inverse: `attach(b, old_supart)`.
    ///
    /// Refused when either body is unknown, `b` is the root, or `supart` is `b` or one of
    /// its parts at any depth ([`WorldError::Cycle`]).
    pub fn attach(&mut self, b: BodyId, supart: BodyId) -> Result<(), WorldError> {
        let node = self.live_part(b, "attached to another body")?;
        let old = node.supart;
        self.live(supart)?;
        if self.tree.is_within(supart, b) {
            return Err(WorldError::Cycle { body: b, supart });
        }
        if old != supart {
            self.relink_in_place(b, supart);
        }
        self.written();
        Ok(())
    }

    /// DETACH(b): ATTACH(b, world), keeping its world pose. Refused for the root or an
    /// unknown body.
    pub fn detach(&mut self, b: BodyId) -> Result<(), WorldError> {
        self.attach(b, self.root())
    }

    /// Names body `b` (`None` removes its name). Refused for the root, an unknown body,
    /// a bad name, or a name another body has.
    pub fn rename(&mut self, b: BodyId, name: Option<&str>) -> Result<(), WorldError> {
        self.live_part(b, "renamed")?;
        let name = name.map(|n| self.free_name(n, Some(b))).transpose()?;
        self.tree.set_name(b, name);
        self.written();
        Ok(())
    }

    /// Sets `b`'s pose relative to its supart (renormalising the quaternion); its parts
    /// move with it. Refused for the root, an unknown body, a bad pose, or one that
    /// would place `b` or a part of it beyond the world's range.
    pub fn set_pose(&mut self, b: BodyId, pose: Pose) -> Result<(), WorldError> {
        self.live_part(b, "posed")?;
        let pose = pose.validated()?;
        let supart = self.tree.supart(b).expect("checked");
        self.check_placement(b, supart, &pose)?;
        self.tree.get_mut(b).expect("checked").pose = pose;
        self.written();
        Ok(())
    }

    /// Sets (or with `None` clears) body `b`'s material colour. Refused for the root or
    /// an unknown body.
    pub fn set_color(&mut self, b: BodyId, color: Option<Color>) -> Result<(), WorldError> {
        self.live_part(b, "coloured")?;
        self.tree.get_mut(b).expect("checked").color = color;
        self.written();
        Ok(())
    }

    /// Renames (`Some(None)` removes the name), re-parents, re-poses and re-colours
    /// (`Some(None)` restores the default colour) body `b` in one write: either all of
    /// the given changes happen, as one revision, or none does.
    /// The re-parenting happens before the new pose is set, so `pose` is relative to the
    /// new supart.
    ///
    /// Refused as [`World::rename`], [`World::attach`] and [`World::set_pose`] are, in
    /// that order. Every check is made before anything changes (none of the three
    /// changes affects whether another is allowed), so the cost is that of the changes
    /// themselves, not of a trial copy of the world.
    ///
    /// Returns whether anything changed. A request whose every given value equals the
    /// body's current one (or that gives none) changes nothing and leaves the revision
    /// as it was; it is still refused as above (an unknown body, say).
    pub fn update(
        &mut self,
        b: BodyId,
        name: Option<Option<&str>>,
        supart: Option<BodyId>,
        pose: Option<Pose>,
        color: Option<Option<Color>>,
    ) -> Result<bool, WorldError> {
        // Plan: the same checks, in the same order, as rename, attach and set_pose.
        let name = match name {
            Some(name) => {
                self.live_part(b, "renamed")?;
                Some(name.map(|n| self.free_name(n, Some(b))).transpose()?)
            }
            None => None,
        };
        if let Some(supart) = supart {
            self.live_part(b, "attached to another body")?;
            self.live(supart)?;
            if self.tree.is_within(supart, b) {
                return Err(WorldError::Cycle { body: b, supart });
            }
        }
        let pose = match pose {
            Some(pose) => {
                self.live_part(b, "posed")?;
                let pose = pose.validated()?;
                let under = match supart {
                    Some(s) => s,
                    None => self.tree.supart(b).expect("checked"),
                };
                self.check_placement(b, under, &pose)?;
                Some(pose)
            }
            None => None,
        };
        if color.is_some() {
            self.live_part(b, "coloured")?;
        }
        // Drop what would not change: a write that changes nothing is no write.
        let node = self.tree.get(b).expect("checked");
        let name = name.filter(|n| *n != node.name);
        let supart = supart.filter(|&s| Some(s) != self.tree.supart(b));
        let pose = pose.filter(|p| supart.is_some() || *p != node.pose);
        let color = color.filter(|c| *c != node.color);
        if name.is_none() && supart.is_none() && pose.is_none() && color.is_none() {
            return Ok(false);
        }
        // Apply: nothing below can fail.
        if let Some(name) = name {
            self.tree.set_name(b, name);
        }
        if let Some(supart) = supart {
            self.relink_in_place(b, supart);
        }
        if let Some(pose) = pose {
            self.tree.get_mut(b).expect("checked").pose = pose;
        }
        if let Some(color) = color {
            self.tree.get_mut(b).expect("checked").color = color;
        }
        self.written();
        Ok(true)
    }

    /// KLBFEV: removes body `b` with all its faces, edges and vertices, and all its
    /// sub-parts at any depth. Their serial numbers are never issued again. Returns what
    /// was removed. Refused for the root or an unknown body.
    pub fn kill(&mut self, b: BodyId) -> Result<Killed, WorldError> {
        self.live_part(b, "killed")?;
        let killed = self.remove_with_parts(b);
        self.written();
        Ok(killed)
    }

    /// KLBFEV's removal without the revision: `b` and all its sub-parts at any depth
    /// leave the tree, for a write that does more than kill (see [`World::boolean`]).
    /// Precondition: `b` lives and is not the root.
    pub(super) fn remove_with_parts(&mut self, b: BodyId) -> Killed {
        Killed {
            bodies: self.tree.remove_subtree(b),
        }
    }
}
