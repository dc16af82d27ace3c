/* motorlab: the dynamometer's hardware on a REV hub. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.hardware.lynx.LynxModule;
import com.qualcomm.robotcore.hardware.DcMotor;
import com.qualcomm.robotcore.hardware.DcMotorEx;
import com.qualcomm.robotcore.hardware.DcMotorSimple;
import com.qualcomm.robotcore.hardware.DigitalChannel;
import com.qualcomm.robotcore.hardware.HardwareMap;
import com.qualcomm.robotcore.hardware.VoltageSensor;
import java.util.List;
import org.firstinspires.ftc.robotcore.external.navigation.CurrentUnit;

/**
 * The motor's encoder (read with MANUAL bulk caching: one bulk read per loop), the optional INA219,
 * the optional relay that connects a bench supply (seed 1's rig), and the hub's battery voltage.
 *
 * <p>Two drives: {@link Drive#RELAY} (a relay on a digital channel switches the bench supply; the hub
 * port only reads the encoder) and {@link Drive#HUB} (the hub port powers the motor; "power cut" is
 * power 0 with ZeroPowerBehavior.FLOAT, i.e. coasting).
 */
public final class DynoRig {
    public enum Drive { RELAY, HUB }

    public final DynoConfig config;
    public final DcMotorEx motor;
    public final List<LynxModule> hubs;
    public final Ina219 ina219;
    public final DigitalChannel relay;
    public final VoltageSensor battery;
    public final Drive drive;
    private double power;
    private boolean relayClosed;
    private double batteryVolts = Double.NaN;
    private Boolean driveOn = null;
    private double driveHubPower = Double.NaN;

    private DynoRig(DynoConfig config, DcMotorEx motor, List<LynxModule> hubs, Ina219 ina219, DigitalChannel relay,
            VoltageSensor battery) {
        this.config = config;
        this.motor = motor;
        this.hubs = hubs;
        this.ina219 = ina219;
        this.relay = relay;
        this.battery = battery;
        this.drive = relay != null ? Drive.RELAY : Drive.HUB;
    }

    /**
     * Find and set up the devices named in {@code config}; the motor is required, the rest optional.
     *
     * @throws IllegalArgumentException when the motor is not configured (the SDK's message)
     * @throws IllegalStateException when the INA219 does not accept its configuration
     */
    public static DynoRig open(HardwareMap map, DynoConfig config) {
        DcMotorEx motor = map.get(DcMotorEx.class, config.motorName);
        List<LynxModule> hubs = map.getAll(LynxModule.class);
        for (LynxModule hub : hubs) {
            hub.setBulkCachingMode(LynxModule.BulkCachingMode.MANUAL);
        }
        Ina219 ina = map.tryGet(Ina219.class, config.ina219Name);
        DigitalChannel relay = map.tryGet(DigitalChannel.class, config.relayName);
        List<VoltageSensor> sensors = map.getAll(VoltageSensor.class);
        DynoRig rig = new DynoRig(config, motor, hubs, ina, relay, sensors.isEmpty() ? null : sensors.get(0));
        motor.setDirection(config.reverse ? DcMotorSimple.Direction.REVERSE : DcMotorSimple.Direction.FORWARD);
        motor.setMode(DcMotor.RunMode.STOP_AND_RESET_ENCODER);
        motor.setMode(DcMotor.RunMode.RUN_WITHOUT_ENCODER); // open loop: the power is the PWM duty
        motor.setZeroPowerBehavior(DcMotor.ZeroPowerBehavior.FLOAT);
        motor.setPower(0.0);
        if (relay != null) {
            relay.setMode(DigitalChannel.Mode.OUTPUT);
            rig.setRelay(false);
        }
        if (ina != null && !ina.configure(config.ina219)) {
            throw new IllegalStateException("INA219 '" + config.ina219Name
                    + "' did not read back its configuration: check wiring, address and power");
        }
        return rig;
    }

    /** Bulk-read the encoder: position [counts] and the hub's velocity [counts/s]. */
    public void readEncoder(Sample s) {
        for (LynxModule hub : hubs) {
            hub.clearBulkCache();
        }
        s.counts = motor.getCurrentPosition();
        s.velocity = motor.getVelocity();
    }

    /**
     * Voltage: the INA219's bus voltage with the relay drive (refusing above its limit); with the hub
     * drive the commanded voltage power·V_battery (the power in effect, the battery read now).
     */
    public void readVoltage(Sample s) {
        s.voltage = drive == Drive.RELAY ? ina219.readBusVoltage() : power * batteryVoltage();
    }

    /** Current: the INA219's if there is one, else the hub's motor current signed by the power. */
    public void readCurrent(Sample s) {
        s.current = ina219 != null ? ina219.readCurrent() : Math.signum(power) * motor.getCurrent(CurrentUnit.AMPS);
    }

    /** The hub's input voltage [V] (read now), or 12 V when no voltage sensor is configured. */
    public double batteryVoltage() {
        batteryVolts = battery != null ? battery.getVoltage() : 12.0;
        return batteryVolts;
    }

    /** The last battery voltage read [V] (NaN before the first). */
    public double lastBatteryVoltage() {
        return batteryVolts;
    }

    /** Connect (true) or disconnect the bench supply. */
    public void setRelay(boolean closed) {
        relayClosed = closed;
        relay.setState(closed == config.relayActiveHigh);
    }

    /** Hub drive: PWM duty in [-1, 1]. */
    public void setPower(double power) {
        this.power = Math.max(-1.0, Math.min(1.0, power));
        motor.setPower(this.power);
    }

    /** Hub drive: command a voltage [V] as power = V / V_battery (the last battery reading). */
    public void setVoltage(double volts) {
        double vb = Double.isNaN(batteryVolts) ? batteryVoltage() : batteryVolts;
        setPower(volts / vb);
    }

    /** Power on (relay closed, or the hub at {@code hubPower}) or off (relay open, or power 0, coasting). */
    public void drive(boolean on, double hubPower) {
        if (driveOn != null && driveOn == on && (drive == Drive.RELAY || hubPower == driveHubPower)) {
            return; // unchanged: no command sent to the hub
        }
        driveOn = on;
        driveHubPower = hubPower;
        if (drive == Drive.RELAY) {
            setRelay(on);
        } else {
            setPower(on ? hubPower : 0.0);
        }
    }

    public boolean isRelayClosed() {
        return relayClosed;
    }

    /** Everything off: relay open and hub power 0. Safe to call at any time, several times. */
    public void stop(DcMotor.ZeroPowerBehavior behaviour) {
        try {
            if (relay != null) {
                setRelay(false);
            }
        } finally {
            motor.setZeroPowerBehavior(behaviour);
            setPower(0.0);
        }
    }
}
