//! ROS 2 actions for long jobs (planning, executing a program): goal, progress feedback, result,
//! cancel — ros2-client's implementation, wired to cellsuite's names and QoS.
//!
//! An action's types come from its `.action` file in `cell_msgs`: for `PlanHotwire` they are
//! `PlanHotwireGoal`, `PlanHotwireResult` and `PlanHotwireFeedback`, and the action type name
//! (`cell_msgs/action/PlanHotwire`) is derived from the goal type.

use anyhow::anyhow;
use cell_msgs::RosMessage;
use ros2_client::{
    action::{ActionClientQosPolicies, ActionServerQosPolicies},
    qos::{Durability, History},
    ActionTypeName, Name, QosProfile, ServiceMapping,
};

use crate::node::CellNode;

pub use ros2_client::action::{
    ActionClient, AsyncActionServer, ExecutingGoalHandle, GoalEndStatus,
};
pub use ros2_client::action_msgs::{GoalId, GoalStatusEnum};

/// Asks for a goal's result, asking again every `retry_every` until `timeout`.
///
/// ROS 2 services are volatile: a reply the server sends before it has matched our reply reader
/// is lost, and the call would wait forever. Asking for a result is idempotent, so asking again
/// is safe; each retry is logged. A retry gives up on the earlier request; the server (ours as
/// rclcpp's, [`crate::goal_server`]) answers every request for the goal, so the retry's answer
/// arrives when the goal ends, or at once if it already has.
pub async fn request_result<G, R, F>(
    client: &ActionClient<G, R, F>,
    goal_id: GoalId,
    retry_every: std::time::Duration,
    timeout: std::time::Duration,
) -> anyhow::Result<(GoalStatusEnum, R)>
where
    G: ros2_client::Message + Clone + 'static,
    R: ros2_client::Message + Clone + 'static,
    F: ros2_client::Message + 'static,
{
    let deadline = tokio::time::Instant::now() + timeout;
    loop {
        let attempt =
            retry_every.min(deadline.saturating_duration_since(tokio::time::Instant::now()));
        match tokio::time::timeout(attempt, client.async_request_result(goal_id)).await {
            Ok(Ok(answer)) => return Ok(answer),
            Ok(Err(e)) => return Err(anyhow!("result of goal {goal_id:?}: {e:?}")),
            Err(_) if tokio::time::Instant::now() < deadline => {
                tracing::debug!("no result for goal {goal_id:?} yet; asking again");
            }
            Err(_) => return Err(anyhow!("no result for goal {goal_id:?} within {timeout:?}")),
        }
    }
}

/// How long [`CellNode::wait_for_action_server`] and [`CellNode::wait_for_service`] wait after
/// discovering a server, for the server to discover us.
pub const SERVER_MATCH_SETTLE: std::time::Duration = std::time::Duration::from_secs(1);

/// `cell_msgs/action/PlanHotwire` from the goal type `cell_msgs/action/PlanHotwire_Goal`.
fn action_type<G: RosMessage>() -> anyhow::Result<ActionTypeName> {
    let action = G::type_name()
        .strip_suffix("_Goal")
        .filter(|_| G::interface_kind() == "action")
        .ok_or_else(|| anyhow!("{} is not an action goal type", G::ROS_NAME))?;
    Ok(ActionTypeName::new(G::package(), action))
}

/// QoS of the action services and topics, as rclcpp's defaults: reliable, volatile services and
/// feedback; status transient-local so a late client sees where goals stand.
fn qos() -> (QosProfile, QosProfile, QosProfile) {
    let service = crate::service::qos();
    let feedback = service.clone();
    let status = QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 });
    (service, feedback, status)
}

impl CellNode {
    /// Waits until an action server for `name` has been discovered (its goal and result request
    /// readers, and its reply and feedback writers), or `timeout`. Returns whether it was.
    ///
    /// Send goals only after this: ROS 2 services are volatile, so a goal sent before the server
    /// is matched is lost. (ros2-client's own `wait_for_service` needs to borrow its node across
    /// the wait, which this runtime's shared node cannot lend.)
    pub async fn wait_for_action_server(&self, name: &str, timeout: std::time::Duration) -> bool {
        let base = self.resolve_topic(name);
        let dds = |prefix: &str, rest: &str| format!("{prefix}{base}/_action/{rest}");
        let readers = [
            dds("rq", "send_goalRequest"),
            dds("rq", "get_resultRequest"),
        ];
        let writers = [
            dds("rr", "send_goalReply"),
            dds("rr", "get_resultReply"),
            dds("rt", "feedback"),
        ];
        self.wait_for_endpoints(&readers, &writers, timeout).await
    }

    /// `name` resolved against namespace and remappings, as text and as a ROS name.
    fn action_name(&self, name: &str) -> anyhow::Result<(String, Name)> {
        let resolved = self.resolve_topic(name);
        let parsed =
            Name::parse(&resolved).map_err(|e| anyhow!("action name {resolved:?}: {e:?}"))?;
        Ok((resolved, parsed))
    }

    /// Serves the action `name` (resolved against namespace and remappings) with goal type `G`,
    /// result `R` and feedback `F`.
    pub fn action_server<G, R, F>(&self, name: &str) -> anyhow::Result<AsyncActionServer<G, R, F>>
    where
        G: RosMessage + ros2_client::Message,
        R: RosMessage + ros2_client::Message,
        F: RosMessage + ros2_client::Message,
    {
        let (resolved, action_name) = self.action_name(name)?;
        let (service, feedback, status) = qos();
        let policies = ActionServerQosPolicies {
            goal_service: service.clone(),
            result_service: service.clone(),
            cancel_service: service,
            feedback_publisher: feedback,
            status_publisher: status,
        };
        let action_type = action_type::<G>()?;
        let server = self
            .with_ros_node(|n| {
                n.create_action_server::<G, R, F>(
                    ServiceMapping::Enhanced,
                    &action_name,
                    &action_type,
                    policies,
                )
            })
            .map_err(|e| anyhow!("action server {resolved}: {e:?}"))?;
        Ok(AsyncActionServer::new(server))
    }

    /// A client of the action `name` (resolved against namespace and remappings).
    pub fn action_client<G, R, F>(&self, name: &str) -> anyhow::Result<ActionClient<G, R, F>>
    where
        G: RosMessage + ros2_client::Message,
        R: RosMessage + ros2_client::Message,
        F: RosMessage + ros2_client::Message,
    {
        let (resolved, action_name) = self.action_name(name)?;
        let (service, feedback, status) = qos();
        let policies = ActionClientQosPolicies {
            goal_service: service.clone(),
            result_service: service.clone(),
            cancel_service: service,
            feedback_subscription: feedback,
            status_subscription: status,
        };
        let action_type = action_type::<G>()?;
        self.with_ros_node(|n| {
            n.create_action_client::<G, R, F>(
                ServiceMapping::Enhanced,
                &action_name,
                &action_type,
                policies,
            )
        })
        .map_err(|e| anyhow!("action client {resolved}: {e:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn action_type_comes_from_the_goal_type() {
        let t = action_type::<cell_msgs::PlanHotwireGoal>().unwrap();
        assert_eq!(
            (t.package_name(), t.type_name()),
            ("cell_msgs", "PlanHotwire")
        );
        assert!(action_type::<cell_msgs::Toolpath>().is_err());
        assert!(action_type::<cell_msgs::PlanHotwireResult>().is_err());
    }
}
