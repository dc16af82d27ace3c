// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix.motorcontrol.can;
import com.ctre.phoenix.motorcontrol.ControlMode;
import com.ctre.phoenix.motorcontrol.DemandType;
public class TalonSRX {
    public Object configVoltageCompSaturation(double voltage) { return null; }
    public void enableVoltageCompensation(boolean enable) {}
    public Object config_kP(int slotIdx, double value) { return null; }
    public Object config_kI(int slotIdx, double value) { return null; }
    public Object config_kD(int slotIdx, double value) { return null; }
    public Object config_kF(int slotIdx, double value) { return null; }
    public void set(ControlMode mode, double demand0, DemandType demand1Type, double demand1) {}
}
