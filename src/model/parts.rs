//! The parts tree: Baumgart's PART/COPART/SUPART links between bodies.
//!
//! Every body hangs from a *supart*, the whole it is a part of; at the top is the world
//! body, which is its own supart and has no geometry. A body's [`Pose`] places its own
//! frame (the frame of its vertex loci) in its supart's frame, so moving a body moves
//! everything attached below it: turn the shoulder and the whole arm follows.
//!
//! [`PartsTree`] holds the nodes and answers the read-only questions (SUPART, the parts
//! list, FDNAME, world poses, subtrees). Its changes are made by [`World`](super::World),
//! which checks every request first and keeps the tree's invariants:
//!
//! * the root is its own supart; every other node's supart is a live node, and the node
//!   appears exactly once in that supart's `parts`;
//! * following suparts from any node reaches the root (no cycles);
//! * a name belongs to at most one node, and the name index agrees with the nodes;
//! * the tree's [`Size`] is the sum of its bodies' counts.

use std::collections::HashMap;
use std::fmt;
use std::ops::{Deref, DerefMut};
use std::sync::Arc;

use imbl::{OrdMap, Vector};
use serde::{Deserialize, Serialize};

use super::body::Body;
use super::ids::{EdgeId, FaceId, Serial, VertexId};
use super::perceived::Perceived;
use super::pose::Pose;

/// A body's id: its serial number, taken from the same world-wide counter as its faces,
/// edges and vertices, so no id of any kind is ever reused.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Debug, Serialize, Deserialize)]
pub struct BodyId(pub Serial);

impl BodyId {
    /// The serial number.
    #[inline]
    pub fn serial(self) -> Serial {
        self.0
    }
    /// The number itself, as the API shows it.
    #[inline]
    pub fn get(self) -> u64 {
        self.0.0
    }
}

impl fmt::Display for BodyId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// What a serial number names inside a body: the body itself, or one of its faces, edges
/// or vertices (by slot id). Also the target of a transform (see
/// [`Transform`](super::Transform)): a body is the set of vertices in its vertex ring, a
/// face the vertices on its perimeter, an edge its two ends, a vertex itself.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Entity {
    /// The body node.
    Body,
    /// A face of the body.
    Face(FaceId),
    /// An edge of the body.
    Edge(EdgeId),
    /// A vertex of the body.
    Vertex(VertexId),
}

/// One body in the parts tree.
///
/// The world hands these out only by shared reference; the tree's links (`supart`,
/// `parts`, `name`) change only through [`World`](super::World)'s checked operations.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BodyNode {
    /// The print name FDNAME finds, unique in the world; `None` for an unnamed body.
    pub name: Option<String>,
    /// The whole this body is a part of (the root is its own supart).
    pub supart: BodyId,
    /// The sub-parts, in the order they were attached (PART, then COPART links). A
    /// persistent vector: a world snapshot shares it, and a write that adds or removes
    /// one part copies a path of it, not the whole list (the root may list every body).
    pub parts: Vector<BodyId>,
    /// This body's frame placed in its supart's frame.
    pub pose: Pose,
    /// The polyhedron, behind an `Arc` so that cloning the world (a snapshot) shares
    /// every body, and a later write copies only the body it changes.
    pub body: Arc<Body>,
    /// The material colour appearance renders the body's faces with; `None` for the
    /// default (a colour chosen from the body's id).
    pub color: Option<Color>,
    /// For a provisional body that perception made: the views that carved it and what
    /// made each face; `None` for an ordinary body.
    pub perceived: Option<Arc<Perceived>>,
}

/// A pleasant, stable default colour for a body without one: a hue from the id, fixed
/// saturation and lightness. The same id always gets the same colour.
pub fn default_color(id: BodyId) -> Color {
    // Golden-ratio hue steps spread consecutive ids around the colour wheel.
    let h = (id.get() as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, l) = (0.45, 0.62);
    let c = (1.0 - (2.0 * l - 1.0f64).abs()) * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let m = l - c / 2.0;
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let to8 = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    Color([to8(r), to8(g), to8(b)])
}

/// A material colour: 8-bit sRGB red, green and blue.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Serialize, Deserialize)]
pub struct Color(pub [u8; 3]);

impl Color {
    /// The `#rrggbb` form.
    pub fn to_hex(self) -> String {
        let [r, g, b] = self.0;
        format!("#{r:02x}{g:02x}{b:02x}")
    }

    /// Parses `#rrggbb` (the `#` is required, hex digits in either case).
    pub fn from_hex(s: &str) -> Option<Color> {
        let hex = s.strip_prefix('#')?;
        if hex.len() != 6 || !hex.is_ascii() {
            return None;
        }
        let channel = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
        Some(Color([channel(0)?, channel(2)?, channel(4)?]))
    }
}

/// The longest name a body, camera or light may have, in characters (Unicode code
/// points, as JSON Schema's `maxLength` counts them).
pub const MAX_NAME_LEN: usize = 128;

/// Checks a body, camera or light name: 1 to [`MAX_NAME_LEN`] characters in Unicode
/// normalization form C, no control, format (bidirectional controls, zero-width
/// characters), line or paragraph separator characters, no U+FFFD replacement character
/// (the mark of bytes that were not UTF-8), no leading or trailing white space. Returns
/// what is wrong.
///
/// So a name reads as it is stored, and two names that look alike are spelled alike.
pub fn validate_name(name: &str) -> Result<(), String> {
    use unicode_properties::{GeneralCategory, UnicodeGeneralCategory};
    if name.is_empty() {
        return Err("the name is empty".to_owned());
    }
    let length = name.chars().count();
    if length > MAX_NAME_LEN {
        return Err(format!(
            "the name is {length} characters long, longer than {MAX_NAME_LEN}"
        ));
    }
    for c in name.chars() {
        let kind = match c.general_category() {
            GeneralCategory::Control => "a control character",
            GeneralCategory::Format => {
                "a format character (bidirectional controls and zero-width characters are refused)"
            }
            GeneralCategory::LineSeparator | GeneralCategory::ParagraphSeparator => {
                "a line or paragraph separator"
            }
            _ if c == char::REPLACEMENT_CHARACTER => {
                "the replacement character, the mark of bytes that were not UTF-8"
            }
            _ => continue,
        };
        return Err(format!("the name contains {kind} (U+{:04X})", c as u32));
    }
    if name.trim() != name {
        return Err("the name begins or ends with white space".to_owned());
    }
    if !unicode_normalization::is_nfc(name) {
        return Err(
            "the name is not in Unicode normalization form C (NFC); normalize it first".to_owned(),
        );
    }
    Ok(())
}

/// Faces, edges and vertices: of one body, or of all the bodies of a tree together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Size {
    /// Live faces.
    pub faces: usize,
    /// Live edges.
    pub edges: usize,
    /// Live vertices.
    pub vertices: usize,
}

impl Size {
    /// The counts of `body`.
    pub fn of(body: &Body) -> Size {
        Size {
            faces: body.face_count(),
            edges: body.edge_count(),
            vertices: body.vertex_count(),
        }
    }

    /// The counts of all the bodies of `nodes` together.
    pub fn total<'a>(nodes: impl IntoIterator<Item = &'a BodyNode>) -> Size {
        nodes
            .into_iter()
            .fold(Size::default(), |s, n| s.plus(Size::of(&n.body)))
    }

    /// These counts with `other`'s added.
    pub fn plus(self, other: Size) -> Size {
        Size {
            faces: self.faces + other.faces,
            edges: self.edges + other.edges,
            vertices: self.vertices + other.vertices,
        }
    }

    /// These counts with `other`'s taken away. Precondition: `other` is part of `self`
    /// (each count at most `self`'s); the inverse of [`Size::plus`].
    pub fn minus(self, other: Size) -> Size {
        Size {
            faces: self.faces - other.faces,
            edges: self.edges - other.edges,
            vertices: self.vertices - other.vertices,
        }
    }
}

/// The bodies of a world and the links between them.
///
/// Both maps are persistent B-trees: cloning the tree (a snapshot of the world) copies
/// two pointers, and a change after a clone copies only the path to the node it changes
/// (a few nodes of 16 entries), so that a world of many bodies costs nothing to snapshot
/// and little to write. The total [`Size`] of the bodies is kept as they are added,
/// changed and removed, so that it is read in constant time.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(from = "StoredTree")]
pub struct PartsTree {
    nodes: OrdMap<BodyId, BodyNode>,
    names: OrdMap<String, BodyId>,
    root: BodyId,
    /// The sum of the nodes' bodies' sizes (not stored: worked out when a tree is read).
    #[serde(skip)]
    size: Size,
}

/// A [`PartsTree`] as it is stored: its nodes, names and root.
#[derive(Deserialize)]
struct StoredTree {
    nodes: OrdMap<BodyId, BodyNode>,
    names: OrdMap<String, BodyId>,
    root: BodyId,
}

impl From<StoredTree> for PartsTree {
    fn from(t: StoredTree) -> PartsTree {
        let size = Size::total(t.nodes.values());
        PartsTree {
            nodes: t.nodes,
            names: t.names,
            root: t.root,
            size,
        }
    }
}

/// A node of a tree borrowed to be changed ([`PartsTree::get_mut`]). When it is dropped,
/// the tree's [`Size`] takes in what was done to the node's body.
pub(crate) struct NodeMut<'a> {
    node: &'a mut BodyNode,
    size: &'a mut Size,
    /// The body's size when the node was borrowed.
    before: Size,
}

impl Deref for NodeMut<'_> {
    type Target = BodyNode;
    fn deref(&self) -> &BodyNode {
        self.node
    }
}

impl DerefMut for NodeMut<'_> {
    fn deref_mut(&mut self) -> &mut BodyNode {
        self.node
    }
}

impl Drop for NodeMut<'_> {
    fn drop(&mut self) {
        let after = Size::of(&self.node.body);
        if after != self.before {
            *self.size = self.size.minus(self.before).plus(after);
        }
    }
}

impl PartsTree {
    /// The name of the root body.
    pub const ROOT_NAME: &'static str = "world";

    /// A tree holding only the root body `root`, named [`Self::ROOT_NAME`], its own
    /// supart, with the identity pose and no geometry.
    pub(crate) fn new(root: BodyId) -> Self {
        let mut nodes = OrdMap::new();
        nodes.insert(
            root,
            BodyNode {
                name: Some(Self::ROOT_NAME.to_owned()),
                supart: root,
                parts: Vector::new(),
                pose: Pose::IDENTITY,
                body: Arc::new(Body::empty()),
                color: None,
                perceived: None,
            },
        );
        let mut names = OrdMap::new();
        names.insert(Self::ROOT_NAME.to_owned(), root);
        Self {
            nodes,
            names,
            root,
            size: Size::default(),
        }
    }

    /// Faces, edges and vertices of all the bodies together. Constant time.
    pub fn size(&self) -> Size {
        self.size
    }

    /// The world body at the top of the tree.
    #[inline]
    pub fn root(&self) -> BodyId {
        self.root
    }

    /// Number of nodes, the root included.
    #[inline]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The node of body `b`, if it lives.
    #[inline]
    pub fn get(&self, b: BodyId) -> Option<&BodyNode> {
        self.nodes.get(&b)
    }

    /// Whether `b` is a live body.
    #[inline]
    pub fn contains(&self, b: BodyId) -> bool {
        self.nodes.contains_key(&b)
    }

    /// SUPART(b): the whole `b` is a part of (the root's is the root).
    pub fn supart(&self, b: BodyId) -> Option<BodyId> {
        self.nodes.get(&b).map(|n| n.supart)
    }

    /// The sub-parts of `b`, in attachment order.
    pub fn parts(&self, b: BodyId) -> Option<&Vector<BodyId>> {
        self.nodes.get(&b).map(|n| &n.parts)
    }

    /// FDNAME: the body with this name.
    pub fn find_by_name(&self, name: &str) -> Option<BodyId> {
        self.names.get(name).copied()
    }

    /// Every node, the root included, in id order.
    pub fn iter(&self) -> impl Iterator<Item = (BodyId, &BodyNode)> + '_ {
        self.nodes.iter().map(|(&id, n)| (id, n))
    }

    /// The suparts of `b` from its own supart up to the root (empty for the root or an
    /// unknown body).
    pub fn ancestors(&self, b: BodyId) -> impl Iterator<Item = BodyId> + '_ {
        let mut cur = if b == self.root { None } else { Some(b) };
        let mut budget = self.nodes.len();
        std::iter::from_fn(move || {
            let s = self.nodes.get(&cur?)?.supart;
            budget = budget.checked_sub(1)?;
            cur = (s != self.root).then_some(s);
            Some(s)
        })
    }

    /// Whether `b` lies in the subtree headed by `top` (`b == top` counts).
    pub fn is_within(&self, b: BodyId, top: BodyId) -> bool {
        b == top || self.ancestors(b).any(|a| a == top)
    }

    /// The subtree headed by `b`, in pre-order (`b` first); empty for an unknown body.
    pub fn subtree(&self, b: BodyId) -> Vec<BodyId> {
        let mut out = Vec::new();
        if !self.contains(b) {
            return out;
        }
        let mut stack = vec![b];
        while let Some(x) = stack.pop() {
            out.push(x);
            if let Some(n) = self.nodes.get(&x) {
                stack.extend(n.parts.iter().rev().copied());
            }
        }
        out
    }

    /// The world pose of `b`: the poses on the path from the root down to `b` composed,
    /// so it maps `b`'s vertex loci to world coordinates. The root's is the identity.
    pub fn world_pose(&self, b: BodyId) -> Option<Pose> {
        let node = self.nodes.get(&b)?;
        Some(self.world_pose_of(b, node))
    }

    /// [`world_pose`](Self::world_pose) of `b` whose node, already looked up, is `node`:
    /// one lookup per supart below the root and none for `b` itself.
    /// Precondition: `node` is `b`'s node.
    pub fn world_pose_of(&self, b: BodyId, node: &BodyNode) -> Pose {
        let mut pose = node.pose;
        if b == self.root {
            return pose;
        }
        // The root's pose is the identity (see `check`): the walk stops below it, so
        // that a body hung from the root costs no look-up.
        let mut at = node.supart;
        for _ in 0..self.nodes.len() {
            if at == self.root {
                break;
            }
            let Some(n) = self.nodes.get(&at) else {
                break;
            };
            pose = n.pose.compose(&pose);
            at = n.supart;
        }
        pose
    }

    /// Checks the tree's invariants and returns every problem found (empty when sound).
    /// The world keeps these; this is for tests and for loading saved worlds.
    pub fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        let Some(root) = self.nodes.get(&self.root) else {
            out.push(format!("root {} has no node", self.root));
            return out;
        };
        if root.supart != self.root {
            out.push("the root is not its own supart".to_owned());
        }
        if root.pose != Pose::IDENTITY {
            out.push("the root's pose is not the identity".to_owned());
        }
        // How many times each body is listed as a part, counted in one pass (not by
        // scanning the supart's list for each body: the root may list every body).
        let mut listed: HashMap<BodyId, usize> = HashMap::with_capacity(self.nodes.len());
        for n in self.nodes.values() {
            for &p in &n.parts {
                *listed.entry(p).or_default() += 1;
            }
        }
        for (&id, n) in &self.nodes {
            if id != self.root {
                match self.nodes.get(&n.supart) {
                    None => out.push(format!("body {id}: supart {} is not live", n.supart)),
                    Some(_) => {
                        // Listed once in all, and (checked below) only by its supart.
                        let k = listed.get(&id).copied().unwrap_or(0);
                        if k != 1 {
                            out.push(format!("body {id} is listed as a part {k} times, not once"));
                        }
                    }
                }
                if self.ancestors(id).last() != Some(self.root) {
                    out.push(format!("body {id} does not reach the root"));
                }
            }
            for &p in &n.parts {
                if self.nodes.get(&p).map(|c| c.supart) != Some(id) {
                    out.push(format!("body {id} lists part {p} whose supart differs"));
                }
            }
            if let Some(name) = &n.name
                && self.names.get(name) != Some(&id)
            {
                out.push(format!("body {id}: name {name:?} is not indexed to it"));
            }
            if !n.pose.is_finite() || (n.pose.rotation.length() - 1.0).abs() > 1e-9 {
                out.push(format!("body {id}: pose is not finite and unit"));
            }
        }
        let size = Size::total(self.nodes.values());
        if size != self.size {
            out.push(format!(
                "the tree's size {:?} is not its bodies' total {size:?}",
                self.size
            ));
        }
        for (name, id) in &self.names {
            if self.nodes.get(id).and_then(|n| n.name.as_deref()) != Some(name.as_str()) {
                out.push(format!(
                    "name {name:?} indexes body {id}, which has another name"
                ));
            }
        }
        out
    }

    // ---- changes, made by the world after it has checked them ----

    /// The node of `b`, to be changed. Callers change only `pose`, `color` and `body`
    /// through this; the tree's size follows the body when the borrow ends.
    pub(crate) fn get_mut(&mut self, b: BodyId) -> Option<NodeMut<'_>> {
        let node = self.nodes.get_mut(&b)?;
        let before = Size::of(&node.body);
        Some(NodeMut {
            node,
            size: &mut self.size,
            before,
        })
    }

    /// Adds a node under `supart`. Preconditions: `id` is new, `supart` lives, `name`
    /// (if any) is valid and free.
    pub(crate) fn add(
        &mut self,
        id: BodyId,
        name: Option<String>,
        supart: BodyId,
        pose: Pose,
        body: Arc<Body>,
    ) {
        debug_assert!(!self.nodes.contains_key(&id) && self.nodes.contains_key(&supart));
        if let Some(n) = &name {
            debug_assert!(!self.names.contains_key(n));
            self.names.insert(n.clone(), id);
        }
        self.nodes
            .get_mut(&supart)
            .expect("supart is live")
            .parts
            .push_back(id);
        self.size = self.size.plus(Size::of(&body));
        self.nodes.insert(
            id,
            BodyNode {
                name,
                supart,
                parts: Vector::new(),
                pose,
                body,
                color: None,
                perceived: None,
            },
        );
    }

    /// DET then ATT: moves `b` (with its subtree) into `supart`'s parts list, last.
    /// Its pose is not changed. Preconditions: both live, `b` is not the root, `supart`
    /// is not within `b`'s subtree.
    pub(crate) fn relink(&mut self, b: BodyId, supart: BodyId) {
        debug_assert!(b != self.root && !self.is_within(supart, b));
        let old = self.nodes[&b].supart;
        if let Some(o) = self.nodes.get_mut(&old) {
            remove_part(&mut o.parts, b);
        }
        self.nodes
            .get_mut(&supart)
            .expect("supart is live")
            .parts
            .push_back(b);
        self.nodes.get_mut(&b).expect("b is live").supart = supart;
    }

    /// Gives `b` a new name (or none). Preconditions: `b` lives; `name` is valid and free
    /// or already `b`'s.
    pub(crate) fn set_name(&mut self, b: BodyId, name: Option<String>) {
        let node = self.nodes.get_mut(&b).expect("b is live");
        if let Some(old) = node.name.take() {
            self.names.remove(&old);
        }
        if let Some(n) = &name {
            self.names.insert(n.clone(), b);
        }
        node.name = name;
    }

    /// Removes `b` and its whole subtree, returning the removed nodes in pre-order.
    /// Precondition: `b` lives and is not the root.
    pub(crate) fn remove_subtree(&mut self, b: BodyId) -> Vec<(BodyId, BodyNode)> {
        debug_assert!(b != self.root);
        let ids = self.subtree(b);
        let supart = self.nodes[&b].supart;
        if let Some(s) = self.nodes.get_mut(&supart) {
            remove_part(&mut s.parts, b);
        }
        ids.into_iter()
            .map(|id| {
                let node = self.nodes.remove(&id).expect("subtree node is live");
                self.size = self.size.minus(Size::of(&node.body));
                if let Some(n) = &node.name {
                    self.names.remove(n);
                }
                (id, node)
            })
            .collect()
    }
}

/// Removes `b` from the parts list `parts`, where it is listed at most once (DET): the
/// others keep their order.
fn remove_part(parts: &mut Vector<BodyId>, b: BodyId) {
    // Ids are issued in increasing order, so a list its bodies were only ever added to
    // is sorted, and a binary search finds `b` in it. A list that is not sorted (a body
    // was attached later) may hide `b` from the search: it is then searched leaf by
    // leaf, each a slice, from the end (the parts attached last are found first).
    let found = parts.binary_search(&b).ok().or_else(|| {
        let mut after = parts.len();
        parts.leaves().rev().find_map(|leaf| {
            after -= leaf.len();
            leaf.iter().position(|&p| p == b).map(|i| after + i)
        })
    });
    if let Some(i) = found {
        parts.remove(i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Serials;
    use crate::model::solids::mkcube;

    /// The root (serial 1), `a` (2) under it and `b` (3) under `a`, each of `a` and `b`
    /// a cube.
    fn root_a_b() -> (PartsTree, BodyId, BodyId) {
        let mut serials = Serials::new();
        let root = BodyId(serials.take());
        let (a, b) = (BodyId(serials.take()), BodyId(serials.take()));
        let mut t = PartsTree::new(root);
        let mut cube = || Arc::new(mkcube(&mut serials, 1.0, 1.0, 1.0).expect("a cube"));
        t.add(a, Some("a".into()), root, Pose::IDENTITY, cube());
        t.add(b, None, a, Pose::IDENTITY, cube());
        (t, a, b)
    }

    fn problems_of(t: &PartsTree, part: &str) -> usize {
        t.check().iter().filter(|p| p.contains(part)).count()
    }

    #[test]
    fn a_sound_tree_passes_and_each_broken_link_or_total_is_named() {
        let (t, a, b) = root_a_b();
        assert_eq!(t.check(), Vec::<String>::new());
        assert_eq!(
            t.size(),
            Size {
                faces: 12,
                edges: 24,
                vertices: 16
            }
        );

        // b listed by the root too: twice in all, once by a body that is not its supart.
        let mut twice = t.clone();
        twice
            .nodes
            .get_mut(&twice.root)
            .expect("root")
            .parts
            .push_back(b);
        assert_eq!(problems_of(&twice, "is listed as a part 2 times"), 1);
        assert_eq!(problems_of(&twice, "whose supart differs"), 1);

        // b dropped from a's list: listed nowhere.
        let mut orphan = t.clone();
        orphan.nodes.get_mut(&a).expect("a").parts.clear();
        assert_eq!(problems_of(&orphan, "is listed as a part 0 times"), 1);

        // A running total that does not match the bodies.
        let mut miscounted = t.clone();
        miscounted.size.faces += 1;
        assert_eq!(problems_of(&miscounted, "is not its bodies' total"), 1);
    }

    /// DET from a parts list of many leaves removes that part wherever it is listed,
    /// keeps the others in order, and leaves a snapshot of the list as it was.
    #[test]
    fn a_part_is_removed_from_a_long_list_wherever_it_is() {
        let ids: Vec<BodyId> = (1..=1000).map(|i| BodyId(Serial(i))).collect();
        let mut parts: Vector<BodyId> = ids.iter().copied().collect();
        let snapshot = parts.clone();
        let mut want = ids.clone();
        for at in [999, 0, 500, 63, 64, 700] {
            let b = want.remove(at.min(want.len() - 1));
            remove_part(&mut parts, b);
            assert_eq!(parts.iter().copied().collect::<Vec<_>>(), want, "after {b}");
        }
        remove_part(&mut parts, BodyId(Serial(5000)));
        assert_eq!(parts.len(), want.len());
        assert_eq!(snapshot.iter().copied().collect::<Vec<_>>(), ids);
        // Out of order (bodies attached later): every part is still found.
        let mut shuffled: Vec<BodyId> = ids.clone();
        shuffled.rotate_left(300);
        shuffled.swap(10, 900);
        let mut parts: Vector<BodyId> = shuffled.iter().copied().collect();
        for b in ids.iter().rev().step_by(7) {
            remove_part(&mut parts, *b);
            shuffled.retain(|p| p != b);
            assert_eq!(
                parts.iter().copied().collect::<Vec<_>>(),
                shuffled,
                "after {b}"
            );
        }
    }

    #[test]
    fn a_tree_of_many_parts_under_one_body_checks_sound() {
        let mut serials = Serials::new();
        let root = BodyId(serials.take());
        let mut t = PartsTree::new(root);
        let empty = Arc::new(Body::empty());
        for _ in 0..20_000 {
            t.add(
                BodyId(serials.take()),
                None,
                root,
                Pose::IDENTITY,
                empty.clone(),
            );
        }
        assert_eq!(t.check(), Vec::<String>::new());
        assert_eq!(t.parts(root).map(Vector::len), Some(20_000));
    }
}
