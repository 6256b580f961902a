"""The worker's messages to the parent: one line of stdout each, ``MARK`` then a JSON object
whose ``event`` is one of ``deck``, ``setup``, ``run``, ``progress``, ``warning``, ``error``,
``done``, and ``alive`` (the heartbeat: every second, with the engine's step and the worker's
monotonic time ``at``; read by the runner's watchdog only). Lines without the mark are
LIGGGHTS' own output. A module of its own so that the parent reads the protocol without
importing the worker (numpy, the engine's bindings)."""

MARK = "@vibrofeed "
