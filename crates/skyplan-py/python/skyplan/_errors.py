"""skyplan's exceptions: one class per failure kind of the planning API."""


class PlanError(Exception):
    """No plan: the base class of every skyplan failure (and the class of internal errors).

    ``kind`` is the planning API's failure kind (``invalid_start``, ``invalid_goal``,
    ``no_path``, ``timeout``, ``bad_request``, ``internal``); the message is the API's, as the
    CLI prints it.
    """

    kind = "internal"


class InvalidStart(PlanError, ValueError):
    """The start is off the map, inside an obstacle or its margin, or not expressible."""

    kind = "invalid_start"


class InvalidGoal(PlanError, ValueError):
    """The goal is off the map, inside an obstacle or its margin, or not expressible."""

    kind = "invalid_goal"


class NoPath(PlanError):
    """Valid request, but the start and goal are not connected."""

    kind = "no_path"


class Timeout(PlanError):
    """The planner's time budget (``time_limit_ms``) ran out before it found a path."""

    kind = "timeout"


class BadInput(PlanError, ValueError):
    """Invalid input: a wrong dtype or shape, NaN, an unknown option, a value out of range."""

    kind = "bad_request"


class Conflict(PlanError):
    """No departure of the window is free of the stored intents of equal or higher priority
    (``Airspace.reserve``); ``conflicts`` lists the blocking intents as ``(id, version)``."""

    kind = "conflict"
    conflicts: list = []


class AirspaceUnavailable(PlanError):
    """The airspace store cannot be reached or failed (``Airspace``)."""

    kind = "store_unavailable"
