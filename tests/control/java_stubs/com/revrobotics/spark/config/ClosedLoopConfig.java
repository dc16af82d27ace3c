// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark.config;
public class ClosedLoopConfig {
    public ClosedLoopConfig pid(double p, double i, double d) { return this; }
    public ClosedLoopConfig velocityFF(double ff) { return this; }
}
