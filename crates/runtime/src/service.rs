//! ROS 2 services for short queries (emit one program, …): one request, one response —
//! ros2-client's implementation, wired to cellsuite's names and QoS.
//!
//! A service's types come from its `.srv` file in `cell_msgs`: for `EmitProgram` they are
//! `EmitProgramRequest` and `EmitProgramResponse`, and the service type name
//! (`cell_msgs/srv/EmitProgram`) is derived from the request type. The DDS topics are ROS 2's
//! (`rq/<name>Request`, `rr/<name>Reply`, enhanced service mapping), so a stock ROS 2 client or
//! server interoperates.
//!
//! ```no_run
//! # use cell_msgs::{EmitProgramRequest as Req, EmitProgramResponse as Resp};
//! # async fn demo(node: cell_runtime::CellNode) -> anyhow::Result<()> {
//! use std::time::Duration;
//! let server = node.service_server::<Req, Resp>("emit_program")?;
//! tokio::spawn(async move {
//!     let shutdown = server.node_shutdown();
//!     server.serve(&shutdown, |_request: Req| async move { Resp::default() }).await
//! });
//! let client = node.service_client::<Req, Resp>("emit_program")?;
//! node.wait_for_service("emit_program", Duration::from_secs(10)).await; // requests sent earlier are lost
//! let response = client.call(Req::default(), Duration::from_secs(10)).await?;
//! # Ok(()) }
//! ```

use std::{future::Future, time::Duration};

use anyhow::anyhow;
use cell_msgs::RosMessage;
use ros2_client::{
    qos::{Durability, History},
    Name, QosProfile, ServiceMapping, ServiceTypeName,
};

use crate::{node::CellNode, shutdown::Shutdown};

pub use ros2_client::service::RmwRequestId as RequestId;

/// QoS of services (and of an action's services), as rclcpp's default: reliable, volatile,
/// keep-last 10.
pub(crate) fn qos() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

/// `cell_msgs/srv/EmitProgram` from the request type `cell_msgs/srv/EmitProgram_Request`.
fn service_type<Req: RosMessage>() -> anyhow::Result<ServiceTypeName> {
    let service = Req::type_name()
        .strip_suffix("_Request")
        .filter(|_| Req::interface_kind() == "srv")
        .ok_or_else(|| anyhow!("{} is not a service request type", Req::ROS_NAME))?;
    Ok(ServiceTypeName::new(Req::package(), service))
}

/// Serves one service: take requests with [`ServiceServer::receive`] and answer each with
/// [`ServiceServer::respond`], or hand both to [`ServiceServer::serve`].
pub struct ServiceServer<Req, Resp>
where
    Req: ros2_client::Message,
    Resp: ros2_client::Message,
{
    name: String,
    node: CellNode,
    server: ros2_client::Server<Req, Resp>,
}

impl<Req, Resp> ServiceServer<Req, Resp>
where
    Req: RosMessage + ros2_client::Message,
    Resp: RosMessage + ros2_client::Message,
{
    /// The resolved service name, e.g. `/cell/emit_program`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The shutdown signal of the node that serves this service.
    pub fn node_shutdown(&self) -> Shutdown {
        self.node.shutdown().clone()
    }

    /// The next request and the id to answer it with. A request that cannot be decoded is
    /// logged and skipped. Cancel-safe: a request is taken only when this completes.
    pub async fn receive(&self) -> (RequestId, Req) {
        loop {
            match self.server.async_receive_request().await {
                Ok(pair) => return pair,
                Err(e) => {
                    tracing::warn!("{}: dropping an undecodable request: {e:?}", self.name);
                    // A reader that keeps failing must not spin the node.
                    tokio::time::sleep(Duration::from_millis(10)).await;
                }
            }
        }
    }

    /// Answers the request `id`.
    ///
    /// # Errors
    /// The response could not be written (the message names the service).
    pub async fn respond(&self, id: RequestId, response: Resp) -> anyhow::Result<()> {
        self.server
            .async_send_response(id, response)
            .await
            .map_err(|e| anyhow!("{}: sending a response: {e:?}", self.name))
    }

    /// Answers every request with `handler`, one request at a time, until `shutdown`. A
    /// response that cannot be sent is logged; serving goes on.
    pub async fn serve<F, Fut>(&self, shutdown: &Shutdown, mut handler: F)
    where
        F: FnMut(Req) -> Fut,
        Fut: Future<Output = Resp>,
    {
        loop {
            let (id, request) = tokio::select! {
                r = self.receive() => r,
                _ = shutdown.requested() => return,
            };
            let response = handler(request).await;
            if let Err(e) = self.respond(id, response).await {
                tracing::warn!("{e:#}");
            }
        }
    }
}

/// Calls one service. Calls through one client are made one at a time.
pub struct ServiceClient<Req, Resp>
where
    Req: ros2_client::Message,
    Resp: ros2_client::Message,
{
    name: String,
    client: ros2_client::Client<Req, Resp>,
    /// A call takes the response stream; two at once could each drop the other's response.
    one_call: tokio::sync::Mutex<()>,
}

impl<Req, Resp> ServiceClient<Req, Resp>
where
    Req: RosMessage + ros2_client::Message,
    Resp: RosMessage + ros2_client::Message,
{
    /// The resolved service name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Sends `request` and waits up to `timeout` for its response.
    ///
    /// ROS 2 services are volatile: a request sent before the server has matched this client
    /// is lost, so call [`CellNode::wait_for_service`] first. The request is sent once (a
    /// service need not be idempotent); on a timeout, decide yourself whether to call again.
    ///
    /// # Errors
    /// The request could not be sent, the response could not be read, or none came in time.
    pub async fn call(&self, request: Req, timeout: Duration) -> anyhow::Result<Resp> {
        let _one = self.one_call.lock().await;
        let exchange = async {
            let id = self
                .client
                .async_send_request(request)
                .await
                .map_err(|e| anyhow!("{}: sending the request: {e:?}", self.name))?;
            self.client
                .async_receive_response(id)
                .await
                .map_err(|e| anyhow!("{}: reading the response: {e:?}", self.name))
        };
        match tokio::time::timeout(timeout, exchange).await {
            Ok(result) => result,
            Err(_) => Err(anyhow!(
                "{}: no response within {:.1} s (is a server up, and was it discovered first?)",
                self.name,
                timeout.as_secs_f64()
            )),
        }
    }
}

impl CellNode {
    /// `name` resolved against namespace and remappings, as text and as a ROS name.
    fn service_name(&self, name: &str) -> anyhow::Result<(String, Name)> {
        let resolved = self.resolve_topic(name);
        let parsed =
            Name::parse(&resolved).map_err(|e| anyhow!("service name {resolved:?}: {e:?}"))?;
        Ok((resolved, parsed))
    }

    /// Serves the service `name` (resolved against namespace and remappings) with request type
    /// `Req` and response type `Resp`.
    pub fn service_server<Req, Resp>(&self, name: &str) -> anyhow::Result<ServiceServer<Req, Resp>>
    where
        Req: RosMessage + ros2_client::Message,
        Resp: RosMessage + ros2_client::Message,
    {
        let (resolved, service_name) = self.service_name(name)?;
        let service_type = service_type::<Req>()?;
        let server = self
            .with_ros_node(|n| {
                n.create_server::<Req, Resp>(
                    ServiceMapping::Enhanced,
                    &service_name,
                    &service_type,
                    qos(),
                    qos(),
                )
            })
            .map_err(|e| anyhow!("service server {resolved}: {e:?}"))?;
        Ok(ServiceServer {
            name: resolved,
            node: self.clone(),
            server,
        })
    }

    /// A client of the service `name` (resolved against namespace and remappings).
    pub fn service_client<Req, Resp>(&self, name: &str) -> anyhow::Result<ServiceClient<Req, Resp>>
    where
        Req: RosMessage + ros2_client::Message,
        Resp: RosMessage + ros2_client::Message,
    {
        let (resolved, service_name) = self.service_name(name)?;
        let service_type = service_type::<Req>()?;
        let client = self
            .with_ros_node(|n| {
                n.create_client::<Req, Resp>(
                    ServiceMapping::Enhanced,
                    &service_name,
                    &service_type,
                    qos(),
                    qos(),
                )
            })
            .map_err(|e| anyhow!("service client {resolved}: {e:?}"))?;
        Ok(ServiceClient {
            name: resolved,
            client,
            one_call: tokio::sync::Mutex::new(()),
        })
    }

    /// Waits until a server of the service `name` has been discovered (its request reader and
    /// reply writer), or `timeout`. Returns whether it was.
    ///
    /// Call only after this: ROS 2 services are volatile, so a request sent before the server
    /// is matched is lost. (ros2-client's own `wait_for_service` needs to borrow its node across
    /// the wait, which this runtime's shared node cannot lend.)
    pub async fn wait_for_service(&self, name: &str, timeout: Duration) -> bool {
        let base = self.resolve_topic(name);
        self.wait_for_endpoints(
            &[format!("rq{base}Request")],
            &[format!("rr{base}Reply")],
            timeout,
        )
        .await
    }

    /// Waits until DDS readers on every topic of `readers` and writers on every topic of
    /// `writers` (DDS topic names, e.g. `rq/emit_programRequest`) have been discovered, then
    /// [`crate::action::SERVER_MATCH_SETTLE`] more so the other side matches us too; or
    /// `timeout`. Returns whether they were.
    pub(crate) async fn wait_for_endpoints(
        &self,
        readers: &[String],
        writers: &[String],
        timeout: Duration,
    ) -> bool {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let participant = self.domain_participant();
            let found_readers: Vec<String> = participant
                .discovered_readers()
                .into_iter()
                .map(|r| r.subscription_topic_data.topic_name().to_string())
                .collect();
            let found_writers: Vec<String> = participant
                .discovered_writers()
                .into_iter()
                .map(|w| w.publication_topic_data.topic_name().to_string())
                .collect();
            if readers.iter().all(|r| found_readers.contains(r))
                && writers.iter().all(|w| found_writers.contains(w))
            {
                // Discovery is symmetric but not simultaneous: give the server time to match
                // our endpoints too, or its first replies are lost (volatile services). On a
                // loaded 2-core machine 200 ms was seen to be too short.
                tokio::time::sleep(crate::action::SERVER_MATCH_SETTLE).await;
                return true;
            }
            if tokio::time::Instant::now() >= deadline {
                return false;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn service_type_comes_from_the_request_type() {
        let t = service_type::<cell_msgs::EmitProgramRequest>().unwrap();
        assert_eq!(
            (t.package_name(), t.type_name()),
            ("cell_msgs", "EmitProgram")
        );
        let t = service_type::<cell_msgs::std_srvs::SetBoolRequest>().unwrap();
        assert_eq!((t.package_name(), t.type_name()), ("std_srvs", "SetBool"));
        assert!(service_type::<cell_msgs::EmitProgramResponse>().is_err());
        assert!(service_type::<cell_msgs::Toolpath>().is_err());
        assert!(service_type::<cell_msgs::PlanHotwireGoal>().is_err());
    }
}
