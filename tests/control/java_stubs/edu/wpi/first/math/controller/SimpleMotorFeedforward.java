// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package edu.wpi.first.math.controller;
public class SimpleMotorFeedforward {
    public SimpleMotorFeedforward(double ks, double kv, double ka) {}
    public double calculate(double velocity) { return 0.0; }
}
