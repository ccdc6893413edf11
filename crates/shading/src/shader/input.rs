//! The shading point a script receives as `s` ([`ShadeInput`]), and what
//! the renderer passes instead to have it written straight into the record
//! Lua reads ([`ShadePoint`]).

/// The shading point a script receives as `s` (`docs/shaders.md` lists the
/// fields as scripts see them). Points and vectors are `[x, y, z]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ShadeInput {
    /// Object-space position (`s.P`).
    pub p: [f32; 3],
    /// World-space position (`s.Pw`).
    pub pw: [f32; 3],
    /// Camera-space position (`s.Pc`): x right, y up, z towards the viewer.
    pub pc: [f32; 3],
    /// Shading normal, world space, unit length (`s.N`).
    pub n: [f32; 3],
    /// Geometric normal, world space, unit length (`s.Ng`).
    pub ng: [f32; 3],
    /// The incident ray's unit direction, world space (`s.I`; `s.V` is `-I`).
    pub i: [f32; 3],
    /// Object-space ∂P/∂u and ∂P/∂v (`s.dPdu`, `s.dPdv`).
    pub dpdu: [f32; 3],
    /// See `dpdu`.
    pub dpdv: [f32; 3],
    /// Object-space change of `P` to the next pixel right and down (`s.dPdx`,
    /// `s.dPdy`): the ray's footprint on the surface.
    pub dpdx: [f32; 3],
    /// See `dpdx`.
    pub dpdy: [f32; 3],
    /// Texture coordinates (`s.uv.u`, `s.uv.v`).
    pub uv: [f32; 2],
    /// The ray's time within the shutter, 0 to 1 (`s.time`).
    pub time: f32,
    /// The footprint's width in object space (`s.filterwidth`): the larger
    /// of `|dPdx|` and `|dPdy|`.
    pub filterwidth: f32,
    /// The geometry's object index (`s.object_id`): a mesh's instances share it.
    pub object_id: u32,
    /// The shaded object's own index (`s.instance_id`); `s.random` is a
    /// repeatable number in [0, 1) derived from it.
    pub instance_id: u32,
    /// Ray depth: 0 for camera rays (`s.depth`).
    pub depth: u32,
    /// The pixel being shaded (`s.pixel_x`, `s.pixel_y`).
    pub pixel: [u32; 2],
    /// World-space change of the point to the next pixel right and down
    /// (`s.dPwdx`, `s.dPwdy`).
    pub dpwdx: [f32; 3],
    /// See `dpwdx`.
    pub dpwdy: [f32; 3],
    /// Camera-space change of the point to the next pixel right and down
    /// (`s.dPcdx`, `s.dPcdy`).
    pub dpcdx: [f32; 3],
    /// See `dpcdx`.
    pub dpcdy: [f32; 3],
    /// Change of the texture coordinates to the next pixel right and down
    /// (`s.duvdx`, `s.duvdy`).
    pub duvdx: [f32; 2],
    /// See `duvdx`.
    pub duvdy: [f32; 2],
}

/// Something a [`ShadeInput`] can be made from where the shading point is
/// written (`shade.rs`): the renderer passes its hit this way, and the
/// point is computed straight into the record Lua reads.
pub trait ShadePoint {
    /// The point as a script sees it. Called where the record is written,
    /// so implementations should be `#[inline(always)]`; the slow paths of
    /// a call (errors, `--debug-pixel`) call it again.
    fn input(&self) -> ShadeInput;
    /// [`ShadeInput::instance_id`] alone (for `s.random`).
    fn instance_id(&self) -> u32;
}

impl ShadePoint for ShadeInput {
    #[inline(always)]
    fn input(&self) -> ShadeInput {
        *self
    }

    #[inline(always)]
    fn instance_id(&self) -> u32 {
        self.instance_id
    }
}
