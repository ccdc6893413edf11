//! A shader's closure as Rust receives it: the tree `material(s)` built from
//! `diffuse{}`, `conductor{}`, `dielectric{}`, `sheen{}`, `emission{}`,
//! `transparent{}` and the combinators (`docs/closures.md`), as plain data
//! the renderer turns into lobes. Nodes are stored children first, so every
//! child's index is below its parent's.

/// Most nodes one closure may have; a larger closure is an error naming
/// the shader.
pub const MAX_NODES: usize = 32;

/// What a node is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NodeKind {
    /// `diffuse{albedo, roughness}`: `c[0]` albedo, `x[0]` roughness.
    #[default]
    Diffuse,
    /// `conductor{f0, edge, roughness, anisotropy}`: `c[0]` f0, `c[1]`
    /// edge, `x[0]` roughness, `x[1]` anisotropy.
    Conductor,
    /// `dielectric{ior, roughness, anisotropy, tint, specular, thin}`:
    /// `c[0]` tint (transmission colour), `c[1]` specular (reflection
    /// tint), `x[0]` ior, `x[1]` roughness, `x[2]` anisotropy, `thin`.
    Dielectric,
    /// `sheen{color, roughness}`: `c[0]` colour, `x[0]` roughness.
    Sheen,
    /// `emission{radiance}`: `c[0]` radiance.
    Emission,
    /// `transparent{color}`: `c[0]` the colour light passes with.
    Transparent,
    /// `a + b`.
    Add,
    /// `w * a`: `c[0]` the weight.
    Scale,
    /// `layer{top = a, base = b}`.
    Layer,
}

impl NodeKind {
    /// Every kind, in the order of its number in the FFI record
    /// (`luster_node.kind` in `prelude.lua`).
    pub const ALL: [NodeKind; 9] = [
        NodeKind::Diffuse,
        NodeKind::Conductor,
        NodeKind::Dielectric,
        NodeKind::Sheen,
        NodeKind::Emission,
        NodeKind::Transparent,
        NodeKind::Add,
        NodeKind::Scale,
        NodeKind::Layer,
    ];

    /// The Lua name: the constructor's, or the combinator's.
    pub fn name(self) -> &'static str {
        match self {
            NodeKind::Diffuse => "diffuse",
            NodeKind::Conductor => "conductor",
            NodeKind::Dielectric => "dielectric",
            NodeKind::Sheen => "sheen",
            NodeKind::Emission => "emission",
            NodeKind::Transparent => "transparent",
            NodeKind::Add => "add",
            NodeKind::Scale => "scale",
            NodeKind::Layer => "layer",
        }
    }
}

/// One node of a closure.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    /// What it is.
    pub kind: NodeKind,
    /// The first child (`Add`, `Scale`; a `Layer`'s top).
    pub a: u8,
    /// The second child (`Add`; a `Layer`'s base).
    pub b: u8,
    /// A thin-walled dielectric.
    pub thin: bool,
    /// Colours, by kind (see [`NodeKind`]).
    pub c: [[f32; 3]; 3],
    /// Numbers, by kind (see [`NodeKind`]).
    pub x: [f32; 3],
}

/// A closure: its nodes and which is the root.
#[derive(Clone, Copy, Debug)]
pub struct Closure {
    /// The nodes, children before parents; `nodes[..len]` are used, the
    /// others may hold anything.
    pub nodes: [Node; MAX_NODES],
    /// How many nodes are used.
    pub len: u8,
    /// The root node's index.
    pub root: u8,
}

impl Default for Closure {
    fn default() -> Closure {
        Closure { nodes: [Node::default(); MAX_NODES], len: 0, root: 0 }
    }
}

/// Two closures are equal when their nodes in use and their roots are
/// (the nodes past the count are never read, and may hold anything).
impl PartialEq for Closure {
    fn eq(&self, o: &Closure) -> bool {
        let n = usize::from(self.len);
        (self.len, self.root) == (o.len, o.root) && self.nodes[..n] == o.nodes[..n]
    }
}

impl Closure {
    /// The root node.
    #[inline]
    pub fn root(&self) -> &Node {
        &self.nodes[self.root as usize]
    }
}

/// One line, node by node (a closure may share a node between parents, so a
/// nested form could repeat it exponentially): `#0 diffuse{albedo=(0.8,
/// 0.8, 0.8), roughness=0} #1 ... root #2`. For `--debug-pixel`.
impl std::fmt::Display for Closure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, n) in self.nodes[..usize::from(self.len)].iter().enumerate() {
            let rgb = |k: usize| format!("({}, {}, {})", n.c[k][0], n.c[k][1], n.c[k][2]);
            let x = &n.x;
            let body = match n.kind {
                NodeKind::Diffuse => format!("albedo={}, roughness={}", rgb(0), x[0]),
                NodeKind::Conductor => {
                    format!("f0={}, edge={}, roughness={}, anisotropy={}", rgb(0), rgb(1), x[0], x[1])
                }
                NodeKind::Dielectric => format!(
                    "ior={}, roughness={}, anisotropy={}, tint={}, specular={}, thin={}",
                    x[0],
                    x[1],
                    x[2],
                    rgb(0),
                    rgb(1),
                    n.thin
                ),
                NodeKind::Sheen => format!("color={}, roughness={}", rgb(0), x[0]),
                NodeKind::Emission => format!("radiance={}", rgb(0)),
                NodeKind::Transparent => format!("color={}", rgb(0)),
                NodeKind::Add => format!("#{} + #{}", n.a, n.b),
                NodeKind::Scale => format!("{} * #{}", rgb(0), n.a),
                NodeKind::Layer => format!("top=#{}, base=#{}", n.a, n.b),
            };
            write!(f, "#{i} {}{{{body}}} ", n.kind.name())?;
        }
        write!(f, "root #{}", self.root)
    }
}
