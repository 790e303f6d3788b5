"""CO-SLEEC on ROS 2 (rclpy) and ROS 1 (rospy). The only package that imports either."""
