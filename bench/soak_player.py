#!/usr/bin/python3
"""Plays a TUM-shaped bag's depth frames through sdf_tracker_node again and again, with stamps that
keep increasing across loops, one frame at a time (the next when the node's ~status for the
previous one has arrived), and every REPORT frames prints the node's resident memory and its mean
milliseconds per frame (tracking + fusion from ~status) over those frames.
  soak_player.py BAG FRAMES NODE_PID [REPORT]"""
import sys
import threading
import time

import rosbag
import rospy
from sensor_msgs.msg import CameraInfo, Image
from sdf_tracker.msg import TrackingStatus


def resident_mb(pid):
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def main():
    bag_path, total, pid = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    report = int(sys.argv[4]) if len(sys.argv) > 4 else 1000
    rospy.init_node("soak_player")
    frames, infos = [], {}
    for topic, msg, _ in rosbag.Bag(bag_path).read_messages(["/camera/depth/image", "/camera/depth/camera_info"]):
        if topic.endswith("camera_info"):
            infos[msg.header.stamp] = msg
        else:
            frames.append(msg)
    frames = [(f, infos[f.header.stamp]) for f in frames]
    period = (frames[-1][0].header.stamp - frames[0][0].header.stamp).to_sec() / max(1, len(frames) - 1)
    loop_s = (frames[-1][0].header.stamp - frames[0][0].header.stamp).to_sec() + period

    answered = threading.Event()
    window = {"ms": 0.0, "n": 0, "failed": 0}

    def on_status(status):
        window["ms"] += status.tracking_ms + status.fusion_ms
        window["n"] += 1
        window["failed"] += status.status != TrackingStatus.OK
        answered.set()

    image_pub = rospy.Publisher("camera/depth/image", Image, queue_size=2)
    info_pub = rospy.Publisher("camera/depth/camera_info", CameraInfo, queue_size=2)
    status_sub = rospy.Subscriber("sdf_tracker/status", TrackingStatus, on_status, queue_size=10)
    deadline = time.monotonic() + 60.0
    while (image_pub.get_num_connections() == 0 or info_pub.get_num_connections() == 0
           or status_sub.get_num_connections() == 0):
        if rospy.is_shutdown() or time.monotonic() > deadline:
            print("the node did not connect within 60 s (is it running as sdf_tracker?)", flush=True)
            sys.exit(1)
        time.sleep(0.1)
    rospy.sleep(1.0)
    print("frames  resident_MB  ms_per_frame  failed", flush=True)
    for n in range(total):
        image, info = frames[n % len(frames)]
        shift = rospy.Duration(loop_s * (n // len(frames)))
        image.header.stamp += shift
        info.header.stamp = image.header.stamp
        # Re-sent until answered: the node's subscriptions connect one by one at the start (a
        # pair it already took is dropped by its stamp, never tracked twice).
        for attempt in range(15):
            answered.clear()
            info_pub.publish(info)
            image_pub.publish(image)
            if answered.wait(2.0):
                break
        else:
            print(f"no status for frame {n} within 30 s", flush=True)
            sys.exit(1)
        image.header.stamp -= shift
        if (n + 1) % report == 0:
            print(f"{n + 1:6d}  {resident_mb(pid):11.1f}  {window['ms'] / max(1, window['n']):12.2f}  {window['failed']:6d}",
                  flush=True)
            window.update(ms=0.0, n=0, failed=0)


if __name__ == "__main__":
    main()
