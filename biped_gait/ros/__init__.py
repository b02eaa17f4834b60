"""ROS 2 layer of biped_gait: thin nodes over the pure core, and MCAP recording.

Importing ``biped_gait.ros.environment`` before rclpy keeps DDS discovery on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) unless the caller chose otherwise. The physics
core (everything outside this package) never imports rclpy.
"""
