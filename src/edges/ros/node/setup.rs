//! The node's DDS entities, in the order `run` creates them (context → node → topics and
//! servers → spinner): the participant and context, each mechanism's topics, the service
//! servers, the spinner, and the tasks that turn what arrives (requests, a robot_description,
//! a namesake, clock ticks) into `Event`s.
//!
//! Everything here runs once, before the loop; a failure is an error of `serve` with its
//! context, not a log line. The tasks spawned here only forward: the loop does the work.

use super::publish::{latched, topics};
use super::{mechanism_entry, Event, Mechanism, Request, Servers};
use crate::edges::ros::msgs::StringMsg;
use crate::edges::ros::{Loaded, Mapping, Network, ServeConfig};
use anyhow::{Context as _, Result};
use futures::StreamExt;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::entities_info::ParticipantEntitiesInfo;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Context, Message, MessageTypeName, Name, Node, QosProfile, RmwRequestId, Server, ServiceMapping, ServiceTypeName};
use std::net::{IpAddr, Ipv4Addr};
use std::rc::Rc;
use std::time::Duration;

/// Joins the DDS domain (only on loopback with `--network loopback`) and creates the ROS 2
/// context on it.
pub(super) fn join_domain(config: &ServeConfig) -> Result<Context> {
    // The service reply writers and request readers keep 256 samples (service_qos): with
    // replies or requests of megabytes the byte bounds are what hold their memory.
    let mut builder = DomainParticipantBuilder::new(config.domain)
        .writer_history_max_bytes(config.max_history_bytes)
        .reader_history_max_bytes(config.max_history_bytes);
    if config.network == Network::Loopback {
        // RustDDS then announces and sends only on 127.0.0.1, and finds same-host participants
        // by unicast to the well-known discovery ports on loopback.
        builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    let participant = builder.build().with_context(|| format!("joining DDS domain {}", config.domain))?;
    Context::from_domain_participant(participant).context("creating the ROS 2 context")
}

/// ros2-client's service mapping for `--mapping`.
pub(super) fn service_mapping(mapping: Mapping) -> ServiceMapping {
    match mapping {
        Mapping::Enhanced => ServiceMapping::Enhanced,
        Mapping::Cyclone => ServiceMapping::Cyclone,
        Mapping::Basic => ServiceMapping::Basic,
    }
}

/// One entry per loaded mechanism, with its topics under `<base>/<token>`; the load order
/// gives the first generations.
pub(super) fn mechanisms(node: &mut Node, base: &str, loaded: Vec<Loaded>) -> Result<Vec<Mechanism>> {
    let mut mechanisms = Vec::new();
    for (k, l) in loaded.into_iter().enumerate() {
        let prefix = format!("{base}/{}", l.token);
        let topics = topics(node, &prefix)?;
        mechanisms.push(mechanism_entry(l, prefix, topics, k as u64));
    }
    Ok(mechanisms)
}

/// Reliable and volatile like rclpy's service default, but deeper than its keep-last 10: a
/// burst of requests (or of replies to one client) must not overwrite unacknowledged ones.
/// The node's participant bounds each writer's history and each reader's topic cache by bytes
/// too (`max_history_bytes`).
pub(super) fn service_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_secs(1)))
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 256 })
}

fn server<Q: Message + Clone + 'static, A: Message + 'static>(node: &mut Node, mapping: ServiceMapping, prefix: &str, name: &str, type_name: &str) -> Result<Server<Q, A>> {
    let service_name = Name::new(prefix, name).with_context(|| format!("service name {prefix}/{name}"))?;
    node.create_server(mapping, &service_name, &ServiceTypeName::new("linkspace_msgs", type_name), service_qos(), service_qos())
        .with_context(|| format!("creating service {prefix}/{name}"))
}

/// The node's service servers, under `base`.
pub(super) fn servers(node: &mut Node, mapping: ServiceMapping, base: &str) -> Result<Rc<Servers>> {
    Ok(Rc::new(Servers {
        solve: server(node, mapping, base, "solve", "Solve")?,
        cancel: server(node, mapping, base, "cancel", "Cancel")?,
        singularities: server(node, mapping, base, "singularities", "Singularities")?,
        inverse_kinematics: server(node, mapping, base, "inverse_kinematics", "InverseKinematics")?,
        classify: server(node, mapping, base, "classify", "Classify")?,
        inverse_kinematics6: server(node, mapping, base, "inverse_kinematics6", "InverseKinematics6")?,
        path_check: server(node, mapping, base, "path_check", "PathCheck")?,
        collisions: server(node, mapping, base, "collisions", "Collisions")?,
        self_motion: server(node, mapping, base, "self_motion", "SelfMotion")?,
        list: server(node, mapping, base, "list_mechanisms", "ListMechanisms")?,
    }))
}

/// Spawns the node's spinner, which serves discovery, parameters and rosout, on `ex`.
pub(super) fn spawn_spinner(node: &mut Node, ex: &smol::LocalExecutor<'_>) -> Result<()> {
    let spinner = node.spinner().context("starting the node's spinner")?;
    ex.spawn(async move {
        if let Err(e) = spinner.spin().await {
            say!("linkspace: spinner stopped: {e:?}");
        }
    })
    .detach();
    Ok(())
}

/// Subscribes to `--robot-description-topic` and forwards every URDF on it into the event
/// channel.
pub(super) fn subscribe_robot_description(node: &mut Node, ex: &smol::LocalExecutor<'_>, topic: &str, events: smol::channel::Sender<Event>) -> Result<()> {
    let (ns, name) = match topic.rsplit_once('/') {
        Some((ns, name)) => (if ns.is_empty() { "/" } else { ns }, name),
        None => ("/", topic),
    };
    let name = Name::new(ns, name).with_context(|| format!("--robot-description-topic {topic}"))?;
    let t = node.create_topic(&name, MessageTypeName::new("std_msgs", "String"), &latched(1)).with_context(|| format!("creating topic {topic}"))?;
    let sub = node.create_subscription::<StringMsg>(&t, Some(latched(1))).with_context(|| format!("subscribing to {topic}"))?;
    ex.spawn(async move {
        let stream = sub.async_stream();
        futures::pin_mut!(stream);
        while let Some(r) = stream.next().await {
            match r {
                Ok((msg, _)) => {
                    if events.send(Event::RobotDescription(msg.data)).await.is_err() {
                        break;
                    }
                }
                Err(e) => say!("linkspace: dropped an undecodable robot_description: {e:?}"),
            }
        }
    })
    .detach();
    Ok(())
}

/// Two nodes of one name on a domain serve the same service names, so each answers the other's
/// clients: warn (once per other participant) when `ros_discovery_info`, where every ROS 2
/// participant lists its nodes and `ros2 node list` reads them, shows this node's name elsewhere.
pub(super) fn watch_for_namesakes(context: &Context, node: &mut Node, ex: &smol::LocalExecutor<'_>, events: smol::channel::Sender<Event>) -> Result<()> {
    let own = context.participant_entities_info().gid();
    let name = node.fully_qualified_name();
    let domain = node.domain_id();
    let qos = latched(64);
    let topic = context
        .create_topic("ros_discovery_info".to_string(), MessageTypeName::new("rmw_dds_common", "ParticipantEntitiesInfo"), &qos)
        .context("creating topic ros_discovery_info")?;
    let sub = node.create_subscription::<ParticipantEntitiesInfo>(&topic, Some(qos)).context("subscribing to ros_discovery_info")?;
    ex.spawn(async move {
        let mut warned = std::collections::BTreeSet::new();
        let stream = sub.async_stream();
        futures::pin_mut!(stream);
        while let Some(r) = stream.next().await {
            let Ok((info, _)) = r else { continue };
            let namesake = info.nodes().iter().any(|n| {
                let ns = n.namespace().trim_end_matches('/');
                format!("{ns}/{}", n.name()) == name
            });
            if info.gid() != own && namesake && warned.insert(info.gid()) {
                let message = format!(
                    "another node named {name} is also on domain {domain}: clients of either get replies from both; give this one another name (--node-name NAME or --ros-args -r __node:=NAME) or namespace"
                );
                if events.send(Event::NameTaken(message)).await.is_err() {
                    break;
                }
            }
        }
    })
    .detach();
    Ok(())
}

/// Forwards every request of `server` into the event channel.
fn forward<Q: Message + Clone + 'static, A: Message + 'static>(
    ex: &smol::LocalExecutor<'_>,
    servers: Rc<Servers>,
    pick: fn(&Servers) -> &Server<Q, A>,
    wrap: fn(RmwRequestId, Q) -> Request,
    events: smol::channel::Sender<Event>,
) {
    ex.spawn(async move {
        // One stream for the server's life, as ros2-client's own server example does, rather
        // than a new reader stream per request.
        let mut requests = pick(&servers).receive_request_stream();
        while let Some(r) = requests.next().await {
            match r {
                Ok((id, q)) => {
                    if events.send(Event::Request(wrap(id, q))).await.is_err() {
                        break;
                    }
                }
                // A sample that does not decode (wrong type or mapping) is dropped here: there
                // is no request id to answer it with.
                Err(e) => say!("linkspace: dropped an undecodable request: {e:?}"),
            }
        }
    })
    .detach();
}

/// Forwards the requests of every service server into the event channel.
pub(super) fn forward_requests(ex: &smol::LocalExecutor<'_>, servers: &Rc<Servers>, tx: &smol::channel::Sender<Event>) {
    forward(ex, servers.clone(), |s| &s.solve, Request::Solve, tx.clone());
    forward(ex, servers.clone(), |s| &s.cancel, Request::Cancel, tx.clone());
    forward(ex, servers.clone(), |s| &s.singularities, Request::Singularities, tx.clone());
    forward(ex, servers.clone(), |s| &s.inverse_kinematics, Request::InverseKinematics, tx.clone());
    forward(ex, servers.clone(), |s| &s.classify, Request::Classify, tx.clone());
    forward(ex, servers.clone(), |s| &s.inverse_kinematics6, Request::InverseKinematics6, tx.clone());
    forward(ex, servers.clone(), |s| &s.path_check, Request::PathCheck, tx.clone());
    forward(ex, servers.clone(), |s| &s.collisions, Request::Collisions, tx.clone());
    forward(ex, servers.clone(), |s| &s.self_motion, Request::SelfMotion, tx.clone());
    forward(ex, servers.clone(), |s| &s.list, |id, _| Request::List(id), tx.clone());
}

/// Spawns the clock: a tick every 50 ms (which answers requests whose wait ran out) and, with
/// `--republish`, the republish period.
pub(super) fn spawn_timers(ex: &smol::LocalExecutor<'_>, republish: Option<Duration>, tx: &smol::channel::Sender<Event>) {
    let ticks = tx.clone();
    ex.spawn(async move {
        loop {
            smol::Timer::after(Duration::from_millis(50)).await;
            if ticks.send(Event::Tick).await.is_err() {
                break;
            }
        }
    })
    .detach();

    if let Some(period) = republish {
        let republish = tx.clone();
        ex.spawn(async move {
            loop {
                smol::Timer::after(period).await;
                if republish.send(Event::Republish).await.is_err() {
                    break;
                }
            }
        })
        .detach();
    }
}
