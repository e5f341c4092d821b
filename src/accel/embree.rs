//! Placeholder: replaced by the Embree wrapper.
use super::{HitBatch, RayApi, RayBatch, RayCaster};
use crate::scene::Geometry;
use crate::Result;
pub struct EmbreeScene;
impl EmbreeScene {
    pub fn new(_g: &Geometry) -> Result<Self> {
        Ok(EmbreeScene)
    }
}
impl RayCaster for EmbreeScene {
    fn name(&self) -> &'static str { "embree" }
    fn intersect_with(&self, _: RayApi, r: &RayBatch, h: &mut HitBatch) { h.reset(r.len()) }
    fn occluded_with(&self, _: RayApi, r: &RayBatch, o: &mut Vec<bool>) { o.clear(); o.resize(r.len(), false) }
    fn default_intersect_api(&self) -> RayApi { RayApi::Packet8 }
    fn default_occluded_api(&self) -> RayApi { RayApi::Stream }
}
