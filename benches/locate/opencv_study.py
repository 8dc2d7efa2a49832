#!/usr/bin/env python3
"""OpenCV on the frames `locate_study` wrote: the issue-27 anchor, side by side, same images.

usage: python3 opencv_study.py DIR        (DIR holds truth.csv and the PGM frames)

Three OpenCV finders, each timed per frame (one thread, cv2.setNumThreads(1)):
  hough        HoughCircles (HOUGH_GRADIENT) alone, radius range from the spec (±25 %)
  hough+otsu   HoughCircles, then the intensity-free centroid (moments) of the Otsu-thresholded
               ROI of 1.5 × the diameter around the circle: OpenPnP-style sub-pixel refinement
  blob         SimpleBlobDetector (area filter from the spec), the keypoint as the centre
Prints bias and RMS (per axis, px) per condition and finder, the found count and ms/frame.
"""
import csv
import math
import sys
import time
from collections import defaultdict

import cv2
import numpy as np

cv2.setNumThreads(1)


def hough(img, d):
    r = d / 2
    c = cv2.HoughCircles(cv2.GaussianBlur(img, (5, 5), 1.0), cv2.HOUGH_GRADIENT, dp=1, minDist=d,
                         param1=100, param2=30, minRadius=int(r * 0.75), maxRadius=int(math.ceil(r * 1.25)))
    if c is None:
        return None
    x, y, _ = c[0][0]
    return float(x), float(y)


def hough_otsu(img, d):
    c = hough(img, d)
    if c is None:
        return None
    x, y = c
    h = int(math.ceil(0.75 * d))
    x0, y0 = max(0, int(x) - h), max(0, int(y) - h)
    roi = img[y0:int(y) + h + 1, x0:int(x) + h + 1]
    _, th = cv2.threshold(roi, 0, 255, cv2.THRESH_BINARY_INV + cv2.THRESH_OTSU)
    m = cv2.moments(th, binaryImage=True)
    if m["m00"] == 0:
        return None
    return x0 + m["m10"] / m["m00"], y0 + m["m01"] / m["m00"]


def blob(img, d):
    p = cv2.SimpleBlobDetector_Params()
    p.filterByColor = True
    p.blobColor = 0
    p.filterByArea = True
    p.minArea = math.pi * (0.375 * d) ** 2
    p.maxArea = math.pi * (0.625 * d) ** 2
    p.filterByCircularity = False
    p.filterByInertia = False
    p.filterByConvexity = False
    det = cv2.SimpleBlobDetector_create(p)
    k = det.detect(img)
    if not k:
        return None
    return float(k[0].pt[0]), float(k[0].pt[1])


def main():
    folder = sys.argv[1]
    finders = [("hough", hough), ("hough+otsu", hough_otsu), ("blob", blob)]
    stats = defaultdict(lambda: {"n": 0, "found": 0, "ex": 0.0, "ey": 0.0, "e2": 0.0, "t": 0.0})
    order = []
    with open(f"{folder}/truth.csv") as f:
        for row in csv.DictReader(f):
            img = cv2.imread(f"{folder}/{row['file']}", cv2.IMREAD_GRAYSCALE)
            x, y, d = float(row["x"]), float(row["y"]), float(row["diameter"])
            cond = row["condition"]
            if cond not in order:
                order.append(cond)
            for name, fn in finders:
                s = stats[(cond, name)]
                t0 = time.perf_counter()
                r = fn(img, d)
                s["t"] += time.perf_counter() - t0
                s["n"] += 1
                if r is not None and math.hypot(r[0] - x, r[1] - y) < d / 2:
                    s["found"] += 1
                    s["ex"] += r[0] - x
                    s["ey"] += r[1] - y
                    s["e2"] += ((r[0] - x) ** 2 + (r[1] - y) ** 2) / 2
    print(f"OpenCV {cv2.__version__}, one thread")
    print(f"{'condition':<30} {'finder':<11} {'found':>7} {'bias x':>9} {'bias y':>9} {'rms':>8} {'ms/frame':>9}")
    for cond in order:
        for name, _ in finders:
            s = stats[(cond, name)]
            n = max(s["found"], 1)
            print(f"{cond:<30} {name:<11} {s['found']:>3}/{s['n']:<3} {s['ex'] / n:>9.4f} {s['ey'] / n:>9.4f} "
                  f"{math.sqrt(s['e2'] / n):>8.4f} {1e3 * s['t'] / s['n']:>9.2f}")


if __name__ == "__main__":
    main()
