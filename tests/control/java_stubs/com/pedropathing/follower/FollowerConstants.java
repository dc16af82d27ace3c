// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.pedropathing.follower;
public class FollowerConstants {
    public FollowerConstants forwardZeroPowerAcceleration(double value) { return this; }
    public FollowerConstants lateralZeroPowerAcceleration(double value) { return this; }
}
