"""Running a synthesized controller on a robot (``docs/robot.md``).

One concept per module: ``loop`` (:class:`~urpc.robot.loop.ControlLoop`, the controller, its
trajectory and state stepped once per sample), ``interface`` (the robot protocol), ``safety`` (the
safety layer), ``watchdog`` (deadline misses), ``runner`` (one run: read, check, step, limit,
send), ``packet`` (the UDP wire format), ``udp`` (the loop's UDP client), ``virtual`` (the
virtual robot: the arm and its lock-step driver) and ``virtual_server`` (the virtual robot's UDP
process).
"""
