// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix6.controls;
public class VelocityVoltage extends ControlRequest {
    public VelocityVoltage(double velocity) {}
    public VelocityVoltage withSlot(int slot) { return this; }
}
