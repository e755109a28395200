"""The station's processors, one per file: relay ingest, vision ingest, referee ingest, world
model, robot feedback, strategy, control, the internal referee, command publishing, tracked
vision out and the log player's feed. Each is a ``backend.processor.Processor``; path
following is in ``backend/control/follow.py``."""

from .common import LatencyStage
from .control import ControlProcessor
from .feedback import FeedbackProcessor
from .internal_referee import InternalRefereeProcessor
from .player import PlayerFeed
from .publisher import CommandPublisher
from .referee import RefereeIngest
from .relay_ingest import RelayIngest
from .strategy import StrategyProcessor
from .tracker import TrackerPublisher
from .vision import VisionIngest
from .world import WorldProcessor

__all__ = ["CommandPublisher", "ControlProcessor", "FeedbackProcessor",
           "InternalRefereeProcessor", "LatencyStage", "PlayerFeed", "RefereeIngest",
           "RelayIngest", "StrategyProcessor", "TrackerPublisher", "VisionIngest",
           "WorldProcessor"]
