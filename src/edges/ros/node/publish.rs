//! The latched topics: each mechanism's publishers under `~/<robot>/` (`Topics`), `/tf_static`,
//! the combined markers, and publishing the latest results again (`--republish`).
//!
//! What a result publishes when its run ends is decided in `runs`; this module owns the QoS
//! of the topics and what is published again later. A failed publish is logged and the node
//! goes on: a topic is never worth stopping the loop for.

use super::Mechanism;
use crate::edges::ros::convert;
use crate::edges::ros::msgs::{self, *};
use anyhow::{Context as _, Result};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Message, MessageTypeName, Name, Node, Publisher, QosProfile};
use std::time::Duration;

/// The publishers of one mechanism, under `~/<robot>/`.
pub(super) struct Topics {
    pub(super) configuration_space: Publisher<BoxSet>,
    pub(super) solve_result: Publisher<BoxSet>,
    pub(super) singularities: Publisher<SingularityReport>,
    pub(super) progress: Publisher<msgs::Progress>,
    pub(super) markers: Publisher<MarkerArray>,
    pub(super) assembly_modes: Publisher<JointState>,
    pub(super) assembly_mode: Publisher<AssemblyMode>,
}

/// Reliable + TransientLocal + KeepLast(depth): a late subscriber still gets the latest.
pub(super) fn latched(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_secs(1)))
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth })
}

fn publisher<M: Message>(node: &mut Node, prefix: &str, name: &str, package: &str, type_name: &str, qos: QosProfile) -> Result<Publisher<M>> {
    let topic_name = Name::new(prefix, name).with_context(|| format!("topic name {prefix}/{name}"))?;
    let topic = node.create_topic(&topic_name, MessageTypeName::new(package, type_name), &qos).with_context(|| format!("creating topic {prefix}/{name}"))?;
    node.create_publisher(&topic, None).with_context(|| format!("creating publisher {prefix}/{name}"))
}

/// Reliable + TransientLocal + KeepLast(depth) with the history depth explicit: RustDDS (patched,
/// vendor/README.md) then holds at most `depth` samples while no reader is matched, and drops
/// acknowledged ones beyond it.
pub(super) fn topics(node: &mut Node, prefix: &str) -> Result<Topics> {
    Ok(Topics {
        configuration_space: publisher(node, prefix, "configuration_space", "linkspace_msgs", "BoxSet", latched(1))?,
        solve_result: publisher(node, prefix, "solve_result", "linkspace_msgs", "BoxSet", latched(1))?,
        singularities: publisher(node, prefix, "singularities", "linkspace_msgs", "SingularityReport", latched(1))?,
        progress: publisher(node, prefix, "progress", "linkspace_msgs", "Progress", latched(1))?,
        markers: publisher(node, prefix, "markers", "visualization_msgs", "MarkerArray", latched(1))?,
        // Deep enough for every assembly mode of one result.
        assembly_modes: publisher(node, prefix, "assembly_modes", "sensor_msgs", "JointState", latched(64))?,
        assembly_mode: publisher(node, prefix, "assembly_mode", "linkspace_msgs", "AssemblyMode", latched(64))?,
    })
}

/// The `/tf_static` publisher, latched so that a late tf listener still gets the frames.
pub(super) fn tf_static(node: &mut Node) -> Result<Publisher<TfMessage>> {
    let tf_topic = node
        .create_topic(&Name::new("/", "tf_static").context("/tf_static")?, MessageTypeName::new("tf2_msgs", "TFMessage"), &latched(1))
        .context("creating topic /tf_static")?;
    node.create_publisher(&tf_topic, None).context("creating publisher /tf_static")
}

/// What `~/<robot>/markers` carries: the configuration-space markers, then the singularity
/// markers after them (one `DELETEALL` first), so that a late subscriber of the latched topic
/// gets both for a linkage that has both.
fn combined_markers(m: &Mechanism) -> Option<MarkerArray> {
    match (&m.published, &m.published_singularities) {
        (None, None) => None,
        (Some((_, a)), None) | (None, Some((_, a))) => Some(a.clone()),
        (Some((_, a)), Some((_, b))) => {
            let mut all = a.clone();
            // Both start with their own DELETEALL; one is enough.
            all.markers.extend(b.markers.iter().filter(|x| x.action != msgs::marker::DELETEALL).cloned());
            Some(all)
        }
    }
}

impl super::State {
    /// Publishes `/tf_static`: each mechanism's `<robot>/joint_space` under its root link.
    pub(super) fn publish_static_transforms(&self) {
        let frames: Vec<(String, String)> = self.mechanisms.iter().map(|m| (m.loaded.root_link.clone(), convert::joint_frame(m.loaded.analysis.mechanism()))).collect();
        if let Err(e) = self.tf_static.publish(convert::static_transforms(&frames)) {
            say!("linkspace: publishing /tf_static: {e:?}");
        }
    }
    /// Publishes the latched markers of mechanism `k` (`combined_markers`).
    pub(super) async fn publish_markers(&self, k: usize) {
        let m = &self.mechanisms[k];
        if let Some(markers) = combined_markers(m) {
            if let Err(e) = m.topics.markers.async_publish(markers).await {
                say!("linkspace: publishing {}/markers: {e:?}", m.prefix);
            }
        }
    }
    /// Publishes that the mechanism has no singularity analysis (ok = false, with the reason),
    /// so that a subscriber learns why instead of waiting.
    pub(super) fn publish_no_singularities(&self, k: usize, reason: String) {
        let m = &self.mechanisms[k];
        let report = SingularityReport { header: convert::header(&convert::joint_frame(m.loaded.analysis.mechanism())), mechanism: m.loaded.analysis.mechanism().to_string(), ok: false, message: reason, ..convert::no_report() };
        if let Err(e) = m.topics.singularities.publish(report) {
            say!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
        }
    }
    /// Publishes every latest configuration space (and its markers) again, stamped now: for
    /// tools that subscribe with volatile durability (RViz's default), and for throughput
    /// measurements.
    pub(super) async fn republish(&mut self) {
        for k in 0..self.mechanisms.len() {
            let m = &mut self.mechanisms[k];
            if let Some((set, _)) = &mut m.published {
                set.header = convert::header(&set.header.frame_id);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    say!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
            }
            if let Some((report, _)) = &mut m.published_singularities {
                report.header = convert::header(&report.header.frame_id);
                if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                    say!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
                }
            }
            self.publish_markers(k).await;
        }
    }
}
