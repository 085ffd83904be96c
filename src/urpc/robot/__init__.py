"""Running a synthesized controller on a robot (``docs/robot.md``).

One concept per module: ``loop`` (:class:`~urpc.robot.loop.ControlLoop`, the controller, its
trajectory and state stepped once per sample), ``interface`` (the robot protocol), ``safety`` (the
safety layer), ``watchdog`` (deadline misses), ``runner`` (one run: read, check, step, limit,
send), ``packet`` (the UDP wire format), ``udp`` (the loop's UDP client) and ``virtual`` (the
virtual robot: the arm, its lock-step driver and its UDP process).
"""
