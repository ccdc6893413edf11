//! The integration tests of luster, one binary: the command line, bad and
//! hostile input, golden images of the course scenes, shaders, volumes,
//! OBJ models, glTF scenes, rays from shaders, split renders, the watch server and the fuzz smoke run.

mod adaptive;
mod aov;
mod attributes;
mod bad_input;
mod camera_gaze;
mod closures;
mod cluster;
mod cluster_camera;
mod common;
mod compare;
mod denoise;
mod derivs;
mod display;
mod distribution;
mod ellipsoid;
mod env_flag;
mod flip_reference;
mod fuzz_smoke;
mod gltf;
mod gltf_bad;
mod gltf_materials;
mod golden;
mod golden_hw3;
mod golden_hw4;
mod golden_hw6;
mod golden_hw7;
mod hdr_lights;
mod hostile;
mod instances;
mod light_transforms;
mod obj;
mod path_tracing;
mod perlin_space;
mod shader_aa;
mod shader_bump_smooth;
mod shader_context;
mod shader_material;
mod shaders;
mod suite;
mod trace;
mod vdb;
mod volpath;
mod volumes;
mod watch;
mod watch_editor;
mod whitted_glass;

mod patterns;
